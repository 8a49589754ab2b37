"""No internal error and no numerical library's warning on inputs a new user writes (issue 40,
item 8).

What is asserted: the diagonal-consistency reduction of a monomial basis gives the same basis as
a plain tuple reference when the monomials' codes exceed int64 (a loop with 120 auxiliaries, where
it raised OverflowError); ``certify`` of a loop with 60 ``sin(k*x)`` terms ends with exit 0, 1 or 2
and no traceback, never 3; a far sample's overflow is an inf without a numpy warning (at its
source); a loop whose simulations overflow prints nothing on stderr; and a numerical warning
raised inside a command is logged, not printed, without changing the filters outside it.
"""

from __future__ import annotations

import itertools
import json
import logging
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.language.modelfile import load_any_model
from lyapcheck.models.language.recast import RecastModel
from lyapcheck.models.engines.recast_numeric import field_values
from lyapcheck.sos import bases
from lyapcheck.sos.polynomials import Monomial

app._register_commands()


def reference_consistent(basis: list[Monomial], support: list[Monomial]) -> list[Monomial]:
    """:func:`bases.diagonally_consistent` on exponent tuples, without codes."""
    kept, supp = list(basis), set(support)
    while True:
        sums = {tuple(x + y for x, y in zip(b, c)) for b, c in itertools.permutations(kept, 2)}
        keep = [m for m in kept if tuple(2 * e for e in m) in supp or tuple(2 * e for e in m) in sums]
        if keep == kept:
            return kept
        kept = keep


@pytest.mark.parametrize("nvars", [3, 122])
def test_diagonal_consistency_is_exact_beyond_int64(nvars: int) -> None:
    """122 variables with exponents up to 3: ``7 ** 122`` is far beyond int64 (the codes are then
    Python integers); 3 variables stay on the int64 path. Both agree with the tuple reference."""
    rng = np.random.default_rng(7)
    basis: list[Monomial] = sorted({tuple(int(e) for e in rng.integers(0, 2, nvars) * rng.integers(0, 4, nvars))
                                    for _ in range(40)})
    support = [tuple(2 * e for e in m) for m in basis[::3]]  # some squares are in the support
    support += [tuple(x + y for x, y in zip(basis[1], basis[2]))]
    got = bases.diagonally_consistent(basis, support)
    assert got == reference_consistent(basis, support)
    assert 0 < len(got) < len(basis)  # both rules acted: the test decides something


def test_the_hyperplane_test_in_many_variables_fits_and_keeps_every_usable_monomial() -> None:
    """122 variables: a million directions of support 3 would not fit (MAX_DIRECTION_ENTRIES), so
    fewer are tested; a monomial whose square is in the support is kept, one beyond every
    support point's exponent is dropped."""
    nvars = 122
    rng = np.random.default_rng(11)
    halves = [tuple(int(e) for e in rng.integers(0, 3, nvars)) for _ in range(30)]
    support = [tuple(2 * e for e in m) for m in halves]
    beyond = [tuple(int(k == i) * 7 for k in range(nvars)) for i in range(5)]  # x_i**7 and no point has 14
    assert bases.direction_count(nvars, bases.DIRECTION_SUPPORT) * (len(support) + 35 + nvars) > \
        bases.MAX_DIRECTION_ENTRIES
    assert bases.inside_half_polytope(halves + beyond, support) == [True] * 30 + [False] * 5


def sixty_sines(folder: Path) -> Path:
    """A two-state loop with 60 ``sin(k*x)`` terms: 120 auxiliaries (a sine and a cosine each)."""
    terms = " - ".join(f"0.001*sin({k}*x)" for k in range(1, 61))
    path = folder / "sines.toml"
    path.write_text(f'[model]\nname = "sixty sines"\nstates = ["x", "y"]\n\n[dynamics]\nx = "y"\n'
                    f'y = "-x - y - {terms}"\n')
    return path


def test_a_loop_with_120_auxiliaries_ends_without_an_internal_error(tmp_path: Path) -> None:
    done = CliRunner().invoke(app.cli, ["certify", str(sixty_sines(tmp_path)), "--classes", "quadratic",
                                        "--no-store", "--json"])
    assert done.exit_code in (0, 1, 2), done.output
    assert "Traceback" not in done.output and "internal error" not in done.output
    if done.exit_code != 2:  # it ran: the class answered (today: too large, in words)
        status = json.loads(done.stdout)["conditions"]["quadratic"]["status"]
        assert status in ("certified", "not_certified", "inconclusive")


ESCAPING = """[model]
name = "exponential escape"
states = ["x", "y"]

[dynamics]
x = "y"
y = "-x - y + 0.1*exp(x) - 0.1"

[domain]
x = [-800, 800]
y = [-10, 10]
"""


def test_a_far_samples_overflow_is_an_escape_without_a_warning(tmp_path: Path) -> None:
    """``exp(800)`` overflows: the true field is inf there (an escape for every caller), and numpy
    does not warn (the suite turns warnings into errors, so a warning fails this test)."""
    path = tmp_path / "escape.toml"
    path.write_text(ESCAPING)
    model = load_any_model(path)
    assert isinstance(model, RecastModel)  # a loop with a function
    F = field_values(model.system, np.array([[800.0, 0.0], [0.5, 0.0]]))
    assert not np.all(np.isfinite(F[0])) and np.all(np.isfinite(F[1]))


def test_a_loop_whose_simulation_overflows_prints_nothing_on_stderr(tmp_path: Path) -> None:
    path = tmp_path / "escape.toml"
    path.write_text(ESCAPING)
    done = CliRunner().invoke(app.cli, ["certify", str(path), "--classes", "roa", "--no-store"])
    assert done.exit_code in (0, 1), done.output
    assert done.stderr == ""


def test_the_command_line_logs_a_numerical_warning_instead_of_printing_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    """The net behind the sources' ``errstate``: a numpy floating-point warning raised inside a
    command goes to the ``lyapcheck.cli`` logger, not to stderr, and the filters are as before
    once the command is done (library code is never filtered)."""
    from lyapcheck import api

    original = api.simulate_model_file

    def overflowing(*args: Any, **kwargs: Any) -> Any:
        np.float64(1e308) * np.float64(10)  # a real numpy overflow, as a far sample gives
        return original(*args, **kwargs)

    monkeypatch.setattr(api, "simulate_model_file", overflowing)
    monkeypatch.delenv("LYAPCHECK_DEBUG", raising=False)
    before = list(warnings.filters)
    path = tmp_path / "decay.toml"
    path.write_text('[model]\nstates = ["x"]\n[dynamics]\nx = "-x"\n[domain]\nx = [-1, 1]\n')
    with caplog.at_level(logging.DEBUG, logger="lyapcheck.cli"):
        done = CliRunner().invoke(app.cli, ["simulate", str(path)])
    assert done.exit_code == 0, done.output
    assert done.stderr == ""
    assert any("overflow encountered" in r.getMessage() for r in caplog.records if r.name == "lyapcheck.cli")
    assert warnings.filters == before
    with pytest.raises(RuntimeWarning, match="overflow"):  # outside a command, the suite's filters again
        np.float64(1e308) * np.float64(10)
