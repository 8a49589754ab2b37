"""The ``lyapcheck`` command group: parse, call :mod:`lyapcheck.api`, map errors to exit codes.

Exit codes (DESIGN.md): 0 success, 1 ran correctly but the answer is negative, 2 bad input or
usage (one line on stderr, no traceback). Heavy libraries (sympy, cvxpy, numpy) are imported
inside the commands so that ``lyapcheck --help`` is instant.
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


def _fail(message: str, code: int) -> None:
    click.echo(f"lyapcheck: error: {message}", err=True)
    sys.exit(code)


def one_line_errors(func: F) -> F:
    """Map library errors to a one-line message and an exit code (never a traceback)."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except (InvalidParameter, InputFileError) as exc:
            _fail(str(exc), EXIT_USAGE)
        except LyapcheckError as exc:
            _fail(str(exc), EXIT_NEGATIVE)
        except KeyboardInterrupt:
            _fail("interrupted", 130)
        except (SystemExit, click.exceptions.Exit, click.ClickException):
            raise
        except OSError as exc:  # an output or input path the system refuses: the user's to fix
            where = f" '{exc.filename}'" if getattr(exc, "filename", None) else ""
            _fail(f"cannot access{where}: {exc.strerror or exc}", EXIT_USAGE)
        except Exception as exc:  # noqa: BLE001 - last resort: a user never sees a traceback
            import os

            if os.environ.get("LYAPCHECK_DEBUG"):
                raise
            _fail(f"internal error ({type(exc).__name__}: {exc}); rerun with LYAPCHECK_DEBUG=1 and report it",
                  EXIT_INTERNAL)

    return wrapper  # type: ignore[return-value]


class _Group(click.Group):
    """Click group whose usage errors also end in exit code 2 with one line."""

    def main(self, *args: Any, **kwargs: Any) -> Any:  # pragma: no cover - exercised via CLI tests
        kwargs.setdefault("standalone_mode", False)
        try:
            return super().main(*args, **kwargs)
        except click.exceptions.NoArgsIsHelpError as exc:
            click.echo(exc.ctx.get_help() if exc.ctx else str(exc))
            sys.exit(EXIT_OK)
        except click.UsageError as exc:
            _fail(exc.format_message().splitlines()[0], EXIT_USAGE)
        except click.exceptions.Exit as exc:
            sys.exit(exc.exit_code)
        except click.Abort:
            _fail("aborted", 130)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="lyapcheck")
def cli() -> None:
    """Machine-checked stability answers for the ILOS/ODS microswimmer paper."""


def emit_json(payload: Any) -> None:
    click.echo(json.dumps(payload, indent=2, sort_keys=False))


def _register_commands() -> None:
    """One module per command; each imports its libraries only when the command runs."""
    from lyapcheck.cli import certify, derive, report, simulate, sweep

    for module in (derive, certify, simulate, sweep, report):
        module.register(cli)


def main() -> None:
    _register_commands()
    cli()


if __name__ == "__main__":  # pragma: no cover
    main()
