"""The ``lyapcheck`` command line: the top layer, one module per command.

:mod:`lyapcheck.cli.app` holds the group, the exit codes and the error mapping; each command
module parses its flags, calls :mod:`lyapcheck.api` and prints. Nothing below this package
imports it (``tests/test_layers.py``).
"""

from lyapcheck.cli.app import cli, main

__all__ = ["cli", "main"]
