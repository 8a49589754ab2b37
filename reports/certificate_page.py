"""The certificate page: one builder for every certificate document, of any model.

:func:`certificate_context` turns a certificate document into the data ``certificate.html.j2``
shows. The page is the same for every model: the verdict, a table of every condition class, one
section per class (asked of :func:`reports.sections.section_for`, which knows which module shows
which class of which model), and the reproducibility block (command, the inputs verbatim,
SHA-256 fingerprints, solver outcomes, package versions). What a page says about its model is
the document's *subject* (:mod:`reports.subjects`), chosen by the document's kind from
:data:`SUBJECTS`: the paper's gains, error dynamics, simulation and claims ledger, or a model
file's tables, field, phase portrait and exact re-check.

Every string in the context is plain text: the template escapes it.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any, Callable, Final

from lyapcheck.errors import InputFileError
from reports.sections import section_for
from reports.subjects.base import STATUS_MEANING, Subject, canonical_json
from reports.subjects.model_file import ModelFileSubject
from reports.subjects.paper import PaperSubject
from reports.subjects.sampled import SampledSubject, is_sampled_document
from reports.subjects.search import ExtremumSubject, TuneSubject
from reports.typeset import Equations, versions
from reports.views import as_dict

#: document kind -> its subject (the paper's documents carry no kind of their own)
SUBJECTS: Final[dict[str, Callable[[dict[str, Any]], Subject]]] = {
    "lyapcheck-model-certificate": ModelFileSubject,
    "lyapcheck-certificate": PaperSubject,
}

#: a model certificate written by a search -> its subject, by the search's table
#: (:data:`lyapcheck.models.surfaces.search_tables.SEARCH_TABLES`): the model's page with the search in front
SEARCH_SUBJECTS: Final[dict[str, Callable[[dict[str, Any]], Subject]]] = {
    "tune": TuneSubject,
    "extremum": ExtremumSubject,
}


def subject_of(doc: dict[str, Any]) -> Subject:
    """The subject of a certificate document (a document of no kind is the paper's; a model
    certificate, of a polynomial loop or of a loop with functions, is a model file's, of a sampled-data
    loop (``[sampling]``) a sampled loop's; one written by a search, ``tune`` or ``--maximize``, is that
    search's)."""
    from lyapcheck.models.surfaces.search_tables import search_table

    table = search_table(doc)
    if table is not None:
        return SEARCH_SUBJECTS[table](doc)
    kind = doc.get("kind")
    if kind == "lyapcheck-model-certificate" and is_sampled_document(doc):  # a plant under held controls
        return SampledSubject(doc)
    make = SUBJECTS.get(kind if isinstance(kind, str) else "", PaperSubject)
    return make(doc)


def _str(value: object) -> str:
    return value if isinstance(value, str) else str(value)


def certificate_context(doc: dict[str, Any], *, ledger: bool = True, simulate: bool = True,
                        recheck: bool = True) -> dict[str, Any]:
    """Everything the certificate template shows (strings unescaped; the template escapes).

    Parameters
    ----------
    doc
        A certificate document: the paper's (``lyapcheck.paper.certificate`` schema) or a model
        file's (``lyapcheck.models.surfaces.certificate``); unknown keys and condition classes are shown
        generically.
    ledger, simulate
        Include the claims ledger (the paper's) and the simulation figures (on for real reports).
    recheck
        Re-check the certificate exactly where its subject can (a model file's; no solver).
    """
    if not isinstance(doc, dict):
        raise InputFileError("a certificate must be a JSON object")
    subject = subject_of(doc)
    eqs = Equations()
    ctx = subject.class_context(eqs)
    conditions = [section_for(subject.model, str(name)).view(str(name), cond, k + 1, ctx)
                  for k, (name, cond) in enumerate(as_dict(doc.get("conditions")).items())]
    context: dict[str, Any] = {"status_meaning": STATUS_MEANING}
    context.update(subject.parts(eqs, ledger=ledger, simulate=simulate))
    eqs.typeset()
    context.update(subject.checked(recheck))
    context.update({
        "subject": subject.template,
        "conditions": conditions,
        "hash_document": hashlib.sha256(canonical_json(doc)).hexdigest(),
        "versions": {**{str(k): _str(v) for k, v in as_dict(doc.get("versions")).items()}, **versions()},
        # every typeset equation, for reports.html to put on shared sheets (one glyph set per sheet)
        "equations": [eq.result for eq in eqs.items if eq.result is not None],
    })
    context["fingerprints"] = subject.fingerprints(context)
    return context


def read_certificate(path: str | Path) -> dict[str, Any]:
    """A certificate file of either kind: the paper's (read exactly as before), or a model certificate.

    Raises
    ------
    InputFileError
        One line: missing, not JSON, not a certificate, or a schema this version does not read.
    """
    from lyapcheck.models.surfaces.certificate import SCHEMA_VERSION, is_model_document, read_json
    from lyapcheck.paper.certificate import read_document

    try:
        return read_document(path)
    except InputFileError as refused:
        # the paper's reader refuses any other kind; only a model certificate is read instead,
        # and any other file keeps the paper's reader's message
        try:
            doc = read_json(path)
        except InputFileError:
            raise refused from None
        if not isinstance(doc, dict) or not is_model_document(doc):
            raise
    if doc.get("schema_version") != SCHEMA_VERSION:
        raise InputFileError(f"'{path}' has schema_version {doc.get('schema_version')!r}; this lyapcheck reads "
                             f"model certificates of version {SCHEMA_VERSION}")
    return doc


__all__ = ["certificate_context", "read_certificate", "subject_of", "SUBJECTS", "SEARCH_SUBJECTS"]
