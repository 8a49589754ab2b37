"""The certificate store: what a search found, kept for the next run of the same problem.

A class's search (SOS programs, the solver, the rounding) is the costly part of a run; what it
finds, a certificate in rationals, is small. The store keeps that certificate under a digest of
the exact problem (the polynomial field the class works on, and what the class searches: its
degrees) and of the code that searches (:data:`SEARCH_SOURCES`). A later run of the same problem
reads it and checks it **exactly again** against the field it derived itself in that run, with the
same exact check a fresh solution gets. So the store is a hint, never a verdict: nothing is
certified from it without the exact check, and a stale, foreign or damaged entry costs only the
search the run would have made anyway (an entry that fails to parse or to check is ignored, and
the search's new certificate replaces it).

Why: a researcher re-runs the same model many times (a report, a notebook, CI); from the second
run on, ``certify`` costs the exact check instead of the search. The run's document says where a
certificate came from (``solver.stored``), and ``--no-store`` (or ``LYAPCHECK_CERTIFICATE_STORE=off``)
makes every run search again.

The entries live in ``<cache>/certificates/`` (:func:`lyapcheck.fileio.cache_dir`), one JSON file
per problem, written atomically; a read-only or full cache is left as it is.
"""

from __future__ import annotations

import contextlib
import contextvars
import hashlib
import json
import os
import stat
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final, Iterator, Mapping

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.sos.polynomials import Poly, Ring

#: ``off`` keeps the store out of every run (neither read nor written); any other value, or none, uses it
STORE_ENV: Final = "LYAPCHECK_CERTIFICATE_STORE"
#: the store's folder inside the cache directory
STORE_FOLDER: Final = "certificates"
#: the sources (relative to the package) whose change changes what a search finds: every entry
#: written by other code is ignored (its exact re-check would still be sound; this keeps a run's
#: certificate the one its own search would find)
SEARCH_SOURCES: Final = ("sos", "models/classes/lyapunov.py", "models/loop/positivity.py", "models/loop/field.py",
                         "models/engines/search.py", "models/engines/store.py", "tolerances.py")
#: an entry larger than this is not written (a certificate of a large program; the search is then
#: repeated in each run rather than filling the cache), nor read (whatever put it there)
MAX_ENTRY_BYTES: Final = 4_000_000


#: set inside :func:`disabled` (per thread and task: a context variable)
_DISABLED: contextvars.ContextVar[bool] = contextvars.ContextVar("lyapcheck_store_disabled", default=False)


def enabled() -> bool:
    """Whether this run reads and writes the store (:data:`STORE_ENV`, :func:`disabled`)."""
    return not _DISABLED.get() and os.environ.get(STORE_ENV, "").strip().lower() != "off"


@contextlib.contextmanager
def disabled() -> Iterator[None]:
    """The store off inside the block: a sweep's points are each a problem of their own, which no
    later run repeats (an interrupted sweep resumes from its own results), so storing them would only
    fill the cache."""
    token = _DISABLED.set(True)
    try:
        yield
    finally:
        _DISABLED.reset(token)


@lru_cache(maxsize=1)
def code_digest() -> str:
    """A digest of :data:`SEARCH_SOURCES` (about 0.5 ms: a dozen small files)."""
    package = Path(__file__).resolve().parents[2]  # lyapcheck/, from lyapcheck/models/engines/store.py
    digest = hashlib.sha256()
    for entry in SEARCH_SOURCES:
        path = package / entry
        for source in sorted(path.glob("*.py")) if path.is_dir() else [path]:
            digest.update(source.relative_to(package).as_posix().encode())
            digest.update(source.read_bytes())
    return digest.hexdigest()


def problem_key(kind: str, problem: Mapping[str, Any]) -> str:
    """The key of one problem: a digest of its kind, its JSON form and :func:`code_digest`."""
    text = json.dumps({"kind": kind, "code": code_digest(), "problem": problem}, sort_keys=True,
                      separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def polynomial_json(ring: Ring, p: Poly) -> list[list[Any]]:
    """``p`` exactly, in a canonical form for a key: ``[[exponents, "coefficient"], ...]``, sorted."""
    return sorted([list(m), str(c)] for m, c in ring.terms(p).items())


def _path(key: str) -> Path:
    from lyapcheck.fileio import cache_dir

    return cache_dir() / STORE_FOLDER / f"{key}.json"


def recall(key: str) -> dict[str, Any] | None:
    """The entry stored under ``key``, or None (none, unreadable, not a regular file, larger than
    :data:`MAX_ENTRY_BYTES`, or not a JSON table)."""
    text = _read_entry(_path(key))
    if text is None:
        return None
    try:
        data = json.loads(text)
    except ValueError:
        return None
    return data if isinstance(data, dict) and data.get("key") == key else None


def _read_entry(path: Path) -> str | None:
    """The text of the regular file at ``path`` (a symlink to one counts), or None.

    Whatever sits at an entry's path is read only if it is a regular file of at most
    :data:`MAX_ENTRY_BYTES`: a FIFO would block the run until a writer came (a class stalled, then
    out of time, so a planted pipe changed a verdict), a device could be endless. The type is
    checked before opening (a device is never opened) and again on the open descriptor (the path
    may have changed in between); the open does not block (``O_NONBLOCK``), and at most the cap
    plus one byte is read, whatever the size said."""
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return None
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    except (OSError, ValueError):
        return None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_ENTRY_BYTES:
            return None
        chunks: list[bytes] = []
        left = MAX_ENTRY_BYTES + 1
        while left > 0:
            chunk = os.read(fd, min(left, 1 << 20))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
        data = b"".join(chunks)
        return data.decode("utf-8") if len(data) <= MAX_ENTRY_BYTES else None
    except (OSError, UnicodeDecodeError):
        return None
    finally:
        os.close(fd)


def keep(key: str, entry: Mapping[str, Any]) -> None:
    """Store ``entry`` under ``key`` (atomically; an unwritable cache or a large entry is skipped)."""
    from lyapcheck.fileio import atomic_write

    text = json.dumps({"key": key, **entry}, separators=(",", ":"))
    if len(text) > MAX_ENTRY_BYTES:
        return
    try:
        atomic_write(_path(key), text)
    except OSError:
        pass  # a read-only or full cache: the next run searches again
