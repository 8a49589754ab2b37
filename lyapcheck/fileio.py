"""Writing output files so that an interruption never leaves one half-written, and reading a JSON input
file with one-line errors."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any

from lyapcheck.errors import InputFileError

#: where lyapcheck keeps what it remembers across runs (unit factors, found certificates), when
#: set; else ``$XDG_CACHE_HOME/lyapcheck`` or ``~/.cache/lyapcheck``
CACHE_DIR_ENV = "LYAPCHECK_CACHE_DIR"


def cache_dir() -> Path:
    """The directory of lyapcheck's caches (:data:`CACHE_DIR_ENV`; not created here)."""
    root = os.environ.get(CACHE_DIR_ENV) or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "lyapcheck")
    return Path(root)


def atomic_write(path: str | Path, data: str | bytes) -> Path:
    """Write `data` to a temporary file beside `path`, then rename it into place.

    The rename is atomic on POSIX file systems: a reader sees either the old file or the
    complete new one. The file follows the process umask like a plain ``open`` would.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data.encode("utf-8") if isinstance(data, str) else data)
        # mkstemp creates the file private (0600); an output is an ordinary file: honour the umask
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return target


def read_json(path: str | Path, what: str = "certificate file") -> Any:
    """A JSON file's value, or an :class:`~lyapcheck.errors.InputFileError` in one line naming ``what``
    and the file: it does not exist, is not valid JSON (or not UTF-8), is nested too deeply to read,
    holds a number Python will not read (an integer of more than 4300 digits), or cannot be read (a
    directory, a device, no permission). Its numbers are the caller's to check
    (:func:`lyapcheck.exact.refuse_oversized_numbers`)."""
    p = Path(path)
    try:
        return json.loads(p.read_text())
    except FileNotFoundError:
        raise InputFileError(f"{what} '{p}' does not exist") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputFileError(f"{what} '{p}' is not valid JSON: {exc}") from None
    except RecursionError:
        raise InputFileError(f"{what} '{p}' is nested too deeply to be read") from None
    except ValueError as exc:  # valid JSON syntax that Python will not read: an integer of > 4300 digits
        raise InputFileError(f"{what} '{p}' cannot be read: {exc}") from None
    except OSError as exc:
        raise InputFileError(f"{what} '{p}' cannot be read: {exc.strerror or exc}") from None
