"""``python -m sweeps SPEC.toml --out RESULTS.zarr ...``: the ``lyapcheck sweep`` command.

Same command line, options and exit codes as ``lyapcheck sweep`` (see
:mod:`lyapcheck.cli_sweep`); useful where the console script is not on the path.
"""

from __future__ import annotations

import sys

from lyapcheck import cli as cli_module
from lyapcheck import cli_sweep


def main() -> None:
    cli_sweep.register(cli_module.cli)
    sys.argv[1:1] = ["sweep"]
    cli_module.main()


if __name__ == "__main__":
    main()
