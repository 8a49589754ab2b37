"""What every command module shares: exit codes, the one-line error mapping, JSON output.

Exit codes (DESIGN.md): 0 success, 1 ran correctly but the answer is negative, 2 bad input or
usage (one line on stderr, no traceback), 3 a bug in lyapcheck. The command modules and the
group (:mod:`lyapcheck.cli.app`) import this module; it imports neither.
"""

from __future__ import annotations

import functools
import json
import sys
from typing import Any, Callable, TypeVar

import click

from lyapcheck.errors import InputFileError, InvalidParameter, LyapcheckError

F = TypeVar("F", bound=Callable[..., Any])

EXIT_OK, EXIT_NEGATIVE, EXIT_USAGE = 0, 1, 2
#: a bug in lyapcheck itself (not in the input): one line, and the traceback with LYAPCHECK_DEBUG=1
EXIT_INTERNAL = 3


def fail(message: str, code: int) -> None:
    click.echo(f"lyapcheck: error: {message}", err=True)
    sys.exit(code)


def one_line_errors(func: F) -> F:
    """Map library errors to a one-line message and an exit code (never a traceback)."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except (InvalidParameter, InputFileError) as exc:
            fail(str(exc), EXIT_USAGE)
        except LyapcheckError as exc:
            fail(str(exc), EXIT_NEGATIVE)
        except KeyboardInterrupt:
            fail("interrupted", 130)
        except (SystemExit, click.exceptions.Exit, click.ClickException):
            raise
        except OSError as exc:  # an output or input path the system refuses: the user's to fix
            where = f" '{exc.filename}'" if getattr(exc, "filename", None) else ""
            fail(f"cannot access{where}: {exc.strerror or exc}", EXIT_USAGE)
        except Exception as exc:  # noqa: BLE001 - last resort: a user never sees a traceback
            import os

            if os.environ.get("LYAPCHECK_DEBUG"):
                raise
            fail(f"internal error ({type(exc).__name__}: {exc}); rerun with LYAPCHECK_DEBUG=1 and report it",
                  EXIT_INTERNAL)

    return wrapper  # type: ignore[return-value]


def emit_json(payload: Any) -> None:
    click.echo(json.dumps(payload, indent=2, sort_keys=False))
