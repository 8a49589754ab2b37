"""What the before/after route scripts (``bench_*_route.py``, issue 41) share: one certification with
the certificate store off, timed, and the digests that say whether a run solved the same programs and
wrote the same certificate as before."""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path
from typing import Any


def loop_kind(text: str, source: str) -> str:
    """``polynomial`` (a polynomial or rational loop) or ``functions`` (a loop with functions)."""
    from lyapcheck.models.language.modelfile import Model, parse_any_model

    return "polynomial" if isinstance(parse_any_model(text, source), Model) else "functions"


def timed_certify(path: Path, **options: Any) -> tuple[Any, float]:
    """``api.certify(model=path, **options)`` with no stored certificate reused (each run searches),
    and its wall time in seconds."""
    from lyapcheck import api
    from lyapcheck.models.engines import store

    start = time.perf_counter()
    with store.disabled():
        found = api.certify(model=path, **options)
    return found, time.perf_counter() - start


def solve_log(result: Any) -> tuple[int, str]:
    """How many solves a class's result made, and the digest of their programs' keys in order."""
    keys = [entry.get("program") for entry in (result.solver or {}).get("solves", [])]
    return len(keys), hashlib.sha256(json.dumps(keys).encode()).hexdigest()[:16]


def certificate_digest(result: Any) -> str:
    """The digest of a result's certificate (of the empty text when it has none)."""
    text = json.dumps(result.certificate, sort_keys=True) if result.certificate is not None else ""
    return hashlib.sha256(text.encode()).hexdigest()[:16]
