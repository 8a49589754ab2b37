"""Writing output files so that an interruption never leaves one half-written."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

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
