"""The ``lyapcheck`` command group: parse, call :mod:`lyapcheck.api`, map errors to exit codes.

Exit codes (DESIGN.md): 0 success, 1 ran correctly but the answer is negative, 2 bad input or
usage (one line on stderr, no traceback). Heavy libraries (sympy, cvxpy, numpy) are imported
inside the commands so that ``lyapcheck --help`` is instant.
"""

from __future__ import annotations

import logging
import os
import sys
import warnings
from typing import Any, Final, TextIO

import click

from lyapcheck.cli.common import EXIT_OK, EXIT_USAGE, fail


class _Group(click.Group):
    """Click group whose usage errors also end in exit code 2 with one line."""

    def main(self, *args: Any, **kwargs: Any) -> Any:  # pragma: no cover - exercised via CLI tests
        kwargs.setdefault("standalone_mode", False)
        try:
            with warnings.catch_warnings():  # the command's run only: the library's filters are not touched
                _warnings_to_log()
                return super().main(*args, **kwargs)
        except click.exceptions.NoArgsIsHelpError as exc:
            click.echo(exc.ctx.get_help() if exc.ctx else str(exc))
            sys.exit(EXIT_OK)
        except click.UsageError as exc:
            fail(exc.format_message().splitlines()[0], EXIT_USAGE)
        except click.exceptions.Exit as exc:
            sys.exit(exc.exit_code)
        except click.Abort:
            fail("aborted", 130)


#: the messages of numpy's floating-point warnings (an overflow on a far sample, treated as an escape)
_NUMPY_FLOATING_POINT: Final = r"(overflow|invalid value|divide by zero|underflow) encountered"


def _warnings_to_log() -> None:
    """Inside a command: Python warnings go to the ``lyapcheck.cli`` logger (debug level, which the
    command line does not print), never to the user's stderr, and numpy's floating-point warnings
    are shown to that logger even where the filters would raise them (a far sample's overflow is
    handled as an escape where it happens; this is the net behind it). ``LYAPCHECK_DEBUG=1`` leaves
    warnings as Python shows them."""
    if os.environ.get("LYAPCHECK_DEBUG"):
        return
    log = logging.getLogger("lyapcheck.cli")

    def show(message: Warning | str, category: type[Warning], filename: str, lineno: int,
             file: TextIO | None = None, line: str | None = None) -> None:
        log.debug("%s:%s: %s: %s", filename, lineno, category.__name__, message)

    warnings.showwarning = show
    warnings.filterwarnings("default", message=_NUMPY_FLOATING_POINT, category=RuntimeWarning)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="lyapcheck")
def cli() -> None:
    """Machine-checked stability answers for any polynomial or rational closed loop, from a model
    file (docs/model-files.md); every `certified` is an exact check that `verify` repeats without a
    solver. Worked example: the ILOS/ODS microswimmer paper (its gain files and flags).

    \b
    lyapcheck certify examples/models/van-der-pol-reversed.toml --out vdp.json
    lyapcheck verify vdp.json
    lyapcheck certify examples/paper.toml
    """


def _register_commands() -> None:
    """One module per command; each imports its libraries only when the command runs."""
    from lyapcheck.cli import certify, derive, report, simulate, sweep, tune

    for module in (derive, certify, simulate, sweep, report, tune):
        module.register(cli)


def main() -> None:
    _register_commands()
    cli()


if __name__ == "__main__":  # pragma: no cover
    main()
