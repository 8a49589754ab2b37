"""The memo of unit factors: pint's answers, remembered across runs, never different from them."""

from __future__ import annotations

import json
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import pytest

from lyapcheck import units
from lyapcheck.errors import InvalidParameter
from lyapcheck.units import Kind, parse_quantity
from tests.conftest import ROOT

CASES = [("0.75 mm", Kind.LENGTH), ("2.8 Hz", Kind.ROTATION), ("17.6 rad/s", Kind.ROTATION), ("45 deg", Kind.ANGLE),
         ("0.088 mm/s", Kind.VELOCITY), ("8.7e-5 N", Kind.FORCE), ("1.5 N*s/m^2", Kind.DRAG_PER_LENGTH)]


@pytest.fixture
def memo_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("LYAPCHECK_CACHE_DIR", str(tmp_path))
    units._remembered_factors.cache_clear()
    yield tmp_path
    units._remembered_factors.cache_clear()


def test_remembered_factors_are_pints_and_give_the_same_values(memo_dir: Path) -> None:
    first = [parse_quantity("x", text, kind) for text, kind in CASES]
    (memo,) = memo_dir.glob("unit-factors-*-pint-*.json")
    stored = json.loads(memo.read_text())
    assert len(stored) == len(CASES)
    for text, kind in CASES:
        unit = text.split(" ", 1)[1]
        assert Fraction(stored[f"{kind.name}|{unit}"]) == units._pint_factor("x", unit, kind, text)
    units._remembered_factors.cache_clear()  # a new run reads the file
    assert [parse_quantity("x", text, kind) for text, kind in CASES] == first
    # a Hz rotation is cycles per second: the memo keeps the 2*pi
    assert Fraction(stored["ROTATION|Hz"]) == Fraction(2 * 3.141592653589793)


def test_a_damaged_memo_is_ignored_and_errors_are_never_remembered(memo_dir: Path) -> None:
    parse_quantity("x", "1 mm", Kind.LENGTH)
    (memo,) = memo_dir.glob("unit-factors-*.json")
    memo.write_text('{"LENGTH|mm": "not a number", "LENGTH|km": ')  # truncated JSON
    units._remembered_factors.cache_clear()
    assert parse_quantity("x", "1 mm", Kind.LENGTH) == Fraction(1, 1000)
    memo.write_text(json.dumps({"LENGTH|mm": "1/0"}))
    units._remembered_factors.cache_clear()
    assert parse_quantity("x", "2 mm", Kind.LENGTH) == Fraction(2, 1000)
    with pytest.raises(InvalidParameter):
        parse_quantity("x", "1 s", Kind.LENGTH)
    with pytest.raises(InvalidParameter):
        parse_quantity("x", "3 1/s", Kind.ROTATION)  # ambiguous for a rotation: refused, not remembered
    assert not any(key.startswith(("LENGTH|s", "ROTATION|1/s")) for key in json.loads(memo.read_text()))


def test_with_the_memo_a_quick_run_does_not_import_pint(memo_dir: Path) -> None:
    code = ("import sys; from lyapcheck.paper.params import problem_from_sources; "
            "problem_from_sources('examples/paper.toml', {}); print('pint' in sys.modules)")
    env = {"LYAPCHECK_CACHE_DIR": str(memo_dir), "PATH": "/usr/bin:/bin"}
    runs = [subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=env,
                           check=True).stdout.strip() for _ in range(2)]
    assert runs == ["True", "False"]  # the first run asks pint and remembers; the second does not need it
