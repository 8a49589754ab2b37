"""The completeness suite of issue 30 (benchmarks/completeness/): its index, and the found/missed
table of its fast subset.

The index tests read files only. The table test runs ``lyapcheck certify FILE --json --classes
quadratic,sos_gas`` in a fresh process for each system of the fast subset (``fast = true`` in
``index.toml``: positives found today in a few seconds, and negatives) through
``benchmarks/bench_completeness.py``, and asserts what the index records: every fast positive
found, no fast negative given a global class. The whole suite and its timings:
``python benchmarks/bench_completeness.py``.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from types import ModuleType

import pytest

from tests.conftest import benchmark_module

ROOT = Path(__file__).resolve().parents[1]
SUITE = ROOT / "benchmarks" / "completeness"


def bench() -> ModuleType:
    """benchmarks/bench_completeness.py as a module (registered: its dataclass needs that)."""
    return benchmark_module("bench_completeness")


INDEX = tomllib.loads((SUITE / "index.toml").read_text())
FAST = [(kind, stem) for kind in ("positive", "negative") for stem, e in INDEX[kind].items() if e.get("fast")]


def test_index_lists_every_model_file_and_nothing_else() -> None:
    for kind in ("positive", "negative"):
        on_disk = {p.stem for p in (SUITE / kind).glob("*.toml")}
        assert on_disk == set(INDEX[kind]), f"{kind}: files and index.toml differ: {on_disk ^ set(INDEX[kind])}"
    assert len(INDEX["positive"]) >= 30
    assert len(INDEX["negative"]) >= 20


def test_every_entry_quotes_its_evidence() -> None:
    for stem, entry in INDEX["positive"].items():
        assert entry["expect"] == "found", stem
        assert entry["expect_today"] in ("found", "missed"), stem
        assert "v" in entry or entry.get("v_rule") in ("lyapunov_equation", "nonpolynomial"), stem
        text = (SUITE / "positive" / f"{stem}.toml").read_text()
        assert "Known Lyapunov function" in text, stem
        if "v" in entry:
            assert f"V = {entry['v']}" in text, f"{stem}: the file's comment does not quote index.toml's V"
    for stem, entry in INDEX["negative"].items():
        assert entry["expect"] == "negative", stem
        assert entry["check"]["kind"], stem
        assert "NOT globally asymptotically stable" in (SUITE / "negative" / f"{stem}.toml").read_text(), stem


def test_every_model_file_loads() -> None:
    from lyapcheck.api import load_model_file

    for kind in ("positive", "negative"):
        for stem, entry in INDEX[kind].items():
            model = load_model_file(SUITE / kind / f"{stem}.toml")
            assert len(model.states) == entry["states"], stem


def test_fast_subset_is_a_handful_of_each() -> None:
    kinds = [kind for kind, _ in FAST]
    assert kinds.count("positive") >= 5 and kinds.count("negative") >= 5
    for kind, stem in FAST:
        if kind == "positive":
            assert INDEX[kind][stem]["expect_today"] == "found", f"{stem}: the fast subset holds positives found today"


@pytest.mark.slow
@pytest.mark.parametrize(("kind", "stem"), FAST, ids=[stem for _, stem in FAST])
def test_fast_subset_table(kind: str, stem: str) -> None:
    outcome = bench().run_system(kind, stem, INDEX[kind][stem], timeout=120.0)
    if kind == "negative":
        assert outcome.certified == [], f"SOUNDNESS VIOLATION: {stem} is not GAS but {outcome.certified} certified it"
    else:
        assert outcome.result == "found", f"{stem}: {outcome.statuses} (index: found today)"
