"""``python -m sweeps SPEC.toml --out RESULTS.zarr ...``: the ``lyapcheck sweep`` command.

Same command line, options and exit codes as ``lyapcheck sweep`` (see
:mod:`lyapcheck.cli.sweep`); useful where the console script is not on the path. This file is
a command-line entry point, so it belongs to the top layer, not to :mod:`sweeps`' library.
"""

from __future__ import annotations

import sys


def main() -> None:
    from lyapcheck.cli import app, sweep

    sweep.register(app.cli)
    sys.argv[1:1] = ["sweep"]
    app.cli()


if __name__ == "__main__":
    main()
