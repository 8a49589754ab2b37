"""One exception hierarchy for the whole toolkit.

::

    LyapcheckError                      base of everything the toolkit raises on purpose
    ├── InvalidParameter (ValueError)   a number, unit or key from outside is out of its range
    ├── InputFileError (ValueError)     a TOML / JSON / store file is missing or corrupt
    │   └── ModelFileError              a model file breaks its contract (file, key, what)
    ├── DerivationError (RuntimeError)  the symbolic engine could not produce a required form
    ├── SolverError (RuntimeError)      a conic solver failed in a way we could not classify
    └── CertificateError (ValueError)   a certificate file fails its schema or exact re-check

The command line maps ``InvalidParameter`` and ``InputFileError`` to exit code 2 with a
one-line message; every other ``LyapcheckError`` is reported in one line too, never as a
traceback.
"""

from __future__ import annotations


class LyapcheckError(Exception):
    """Base class of every error the toolkit raises deliberately."""


class InvalidParameter(LyapcheckError, ValueError):
    """A value that entered from outside (TOML, flag, spec) is not acceptable.

    The message always names the field, the accepted range or unit, and what was given.
    """

    def __init__(self, field: str, expected: str, got: object) -> None:
        self.field = field
        self.expected = expected
        self.got = got
        super().__init__(f"The '{field}' parameter must be {expected}. Got {got!r} instead.")


class InputFileError(LyapcheckError, ValueError):
    """An input file is missing, unreadable or not in the expected format."""


class ModelFileError(InputFileError):
    """A model file (or a ``--set`` / ``--candidate`` / ``--box`` given with it) breaks the contract.

    The message is one line: the file, the key (``[dynamics] x2``) and what is wrong there.
    """

    def __init__(self, source: str, key: str, message: str) -> None:
        self.source = source
        self.key = key
        super().__init__(f"{source}: {key}: {message}")


class DerivationError(LyapcheckError, RuntimeError):
    """The symbolic engine could not derive or compare an equation."""


class SolverError(LyapcheckError, RuntimeError):
    """A numerical solver failed in a way that is not a plain infeasibility."""


class CertificateError(LyapcheckError, ValueError):
    """A certificate file is malformed or one of its exact checks fails."""
