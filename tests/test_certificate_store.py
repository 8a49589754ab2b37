"""The certificate store (lyapcheck.models.engines.store): a certificate found by a search is kept, and a
later run of the same problem uses it only after the same exact check a fresh one gets.

What is asserted: the second run solves nothing and says where its certificate came from, with
the same claims as the first, and ``verify`` accepts its document; an entry that was altered, that
belongs to another loop, or that is not JSON is ignored (the run searches, and its certificate
replaces the entry); ``--no-store`` neither reads nor writes; a rational loop's denominators are
stored too; a run whose certificates all come from the store imports neither numpy nor the
solver. The suite itself runs with the store off (tests/conftest.py).
"""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
import threading
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from lyapcheck import api
from lyapcheck.cli import app
from lyapcheck.exact import least_squares
from lyapcheck.models.engines import store
from reports.subjects.model_file import solvers
from tests.conftest import ROOT

POSITIVE = ROOT / "benchmarks" / "completeness" / "positive"
QUARTIC = POSITIVE / "duffing-damped.toml"  # sos_gas at degree 4, after degree 2 fails
RATIONAL = POSITIVE / "sosdemo2-rational.toml"  # a denominator proved positive first

app._register_commands()


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The store on, in a fresh cache directory."""
    monkeypatch.setenv("LYAPCHECK_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv(store.STORE_ENV, "on")
    return tmp_path / store.STORE_FOLDER


def sos_gas(path: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    result = api.certify(model=str(path), classes="sos_gas")
    return result.document, result.document["conditions"]["sos_gas"]


def entries(folder: Path) -> list[Path]:
    return sorted(folder.glob("*.json")) if folder.is_dir() else []


def test_a_stored_certificate_is_rechecked_and_used(cache: Path) -> None:
    _, first = sos_gas(QUARTIC)
    assert first["status"] == "certified" and first["degree"] == 4
    assert len(first["solver"]["solves"]) > 2 and "stored" not in first["solver"]
    assert len(entries(cache)) == 1
    doc, second = sos_gas(QUARTIC)
    assert second["solver"]["solves"] == []
    assert second["solver"]["stored"] == {"key": entries(cache)[0].stem, "check": "exact, in this run"}
    for key in ("status", "summary", "degree", "decay_rate_V_per_s", "certificate"):
        assert second[key] == first[key], key
    assert first["relative_margin"] > 0 and second["relative_margin"] is None  # a solver's figure: no solve ran
    assert api.verify(doc).valid
    [(name, said)] = solvers({"sos_gas": second})  # the report's solver outcomes say it
    assert name == "sos_gas" and said.startswith("no solve") and "re-checked exactly" in said


def _altered(path: Path, change: Any) -> None:
    entry = json.loads(path.read_text())
    change(entry["found"])
    path.write_text(json.dumps(entry))


@pytest.mark.parametrize("change", [
    pytest.param(lambda f: f["W"]["Q"][0].__setitem__(0, str(Fraction(f["W"]["Q"][0][0]) * 2)), id="identity broken"),
    pytest.param(lambda f: f.__setitem__("mu", "1000"), id="decay rate raised"),
    pytest.param(lambda f: f.__setitem__("degree", 2), id="degree misstated"),
    pytest.param(lambda f: f["V"].__setitem__("Q", [["1"]]), id="malformed Gram matrix"),
])
def test_an_altered_entry_is_ignored_and_replaced(cache: Path, change: Any) -> None:
    _, first = sos_gas(QUARTIC)
    [path] = entries(cache)
    _altered(path, change)
    _, again = sos_gas(QUARTIC)
    assert "stored" not in again["solver"] and again["solver"]["solves"]  # searched again
    assert again["certificate"] == first["certificate"]
    _, third = sos_gas(QUARTIC)  # the search's certificate replaced the altered entry
    assert "stored" in third["solver"]


def test_another_loops_entry_or_a_broken_file_is_ignored(cache: Path) -> None:
    sos_gas(POSITIVE / "damped-oscillator.toml")
    [other] = entries(cache)
    sos_gas(QUARTIC)
    mine = next(p for p in entries(cache) if p != other)
    foreign = json.loads(other.read_text())
    foreign["key"] = mine.stem  # the oscillator's quadratic certificate under the Duffing loop's key
    mine.write_text(json.dumps(foreign))
    _, again = sos_gas(QUARTIC)
    assert again["status"] == "certified" and "stored" not in again["solver"]
    mine.write_text("{not json")
    _, again = sos_gas(QUARTIC)
    assert again["status"] == "certified" and "stored" not in again["solver"]


def test_no_store_neither_reads_nor_writes(cache: Path) -> None:
    runner = CliRunner()
    done = runner.invoke(app.cli, ["certify", str(QUARTIC), "--classes", "sos_gas", "--json", "--no-store"])
    assert done.exit_code == 0, done.output
    assert entries(cache) == []
    os.environ[store.STORE_ENV] = "on"  # the flag set it off for the command's process (monkeypatch restores)
    sos_gas(QUARTIC)
    assert len(entries(cache)) == 1
    done = runner.invoke(app.cli, ["certify", str(QUARTIC), "--classes", "sos_gas", "--json", "--no-store"])
    cond = json.loads(done.output)["conditions"]["sos_gas"]
    assert "stored" not in cond["solver"] and cond["solver"]["solves"]


def test_a_rational_loops_denominator_proof_is_stored(cache: Path) -> None:
    doc1, first = sos_gas(RATIONAL)
    assert first["status"] == "certified" and doc1["field"]["denominators"]
    doc2, second = sos_gas(RATIONAL)
    assert "stored" in second["solver"]
    assert doc2["field"]["denominators"] == doc1["field"]["denominators"]
    assert api.verify(doc2).valid


def test_a_run_from_the_store_loads_no_floating_point_code(cache: Path) -> None:
    """The stored path is exact arithmetic alone: numpy, scipy and Clarabel stay unloaded (a
    structural check of what makes a repeated run fast; no timing)."""
    code = ("import sys, json; from lyapcheck import api; "
            f"r = api.certify(model={str(QUARTIC)!r}, classes='sos_gas'); "
            "c = r.document['conditions']['sos_gas']; "
            "print(json.dumps([c['status'], 'stored' in c['solver'], "
            "sorted(m for m in ('numpy', 'scipy', 'clarabel') if m in sys.modules)]))")
    env = {**os.environ, "LYAPCHECK_CACHE_DIR": str(cache.parent), store.STORE_ENV: "on"}
    runs = [json.loads(subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True,
                                      text=True, check=True).stdout) for _ in range(2)]
    assert runs[0] == ["certified", False, ["clarabel", "numpy", "scipy"]]
    assert runs[1] == ["certified", True, []]


def test_the_key_follows_the_problem() -> None:
    base = {"class": "sos_gas", "g": [[[1, 0], "-1"]]}
    assert store.problem_key("lyapunov", base) == store.problem_key("lyapunov", dict(base))
    assert store.problem_key("lyapunov", base) != store.problem_key("lyapunov", {**base, "g": [[[1, 0], "-2"]]})
    assert store.problem_key("lyapunov", base) != store.problem_key("positivity", base)


def test_exact_least_squares_matches_the_floating_point_one() -> None:
    rng = np.random.default_rng(3)
    for rows, cols in ((6, 3), (20, 5), (9, 9)):
        A = rng.integers(-3, 4, size=(rows, cols)).astype(float)
        A[:cols] += 10 * np.eye(cols)  # full column rank
        b = rng.normal(size=rows)
        exact = least_squares([[Fraction(x) for x in row] for row in A], [Fraction(x) for x in b])
        floating, *_ = np.linalg.lstsq(A, b, rcond=None)
        assert np.allclose([float(x) for x in exact], floating, rtol=1e-10, atol=1e-12)
    with pytest.raises(ValueError, match="singular"):
        least_squares([[1, 2], [2, 4]], [1, 2])


def test_inside_disabled_nothing_is_read_or_written(cache: Path) -> None:
    """What a sweep's points run under (sweeps.evaluate): each point is a problem of its own."""
    with store.disabled():
        assert not store.enabled()
        _, cond = sos_gas(QUARTIC)
    assert cond["status"] == "certified" and entries(cache) == []
    assert store.enabled()


class _Writer:
    """A writer waiting on a FIFO: it releases any reader that opens the FIFO (so a test that
    would otherwise stall ends), and records that one did."""

    def __init__(self, fifo: Path) -> None:
        self.fifo, self.opened = fifo, threading.Event()
        self.thread = threading.Thread(target=self._write, daemon=True)
        self.thread.start()

    def _write(self) -> None:
        try:
            with open(self.fifo, "w") as pipe:  # blocks until a reader opens the FIFO
                self.opened.set()
                pipe.write("{not json")
        except BrokenPipeError:  # the reader was release()'s, which closes at once: nothing to write to
            pass

    def release(self) -> bool:
        """Whether a reader opened the FIFO; then ends the writer (by opening it as the reader)."""
        was = self.opened.is_set()
        if not was and self.fifo.exists() and stat.S_ISFIFO(self.fifo.stat().st_mode):
            os.close(os.open(self.fifo, os.O_RDONLY | os.O_NONBLOCK))
        self.thread.join(timeout=30)
        return was


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="FIFOs are POSIX")
def test_a_fifo_at_an_entrys_path_is_not_read(cache: Path) -> None:
    """A pipe where an entry should be is ignored without opening it: no stall (a reader would
    wait for a writer), and the class's result is the one a run without the store gets."""
    with store.disabled():
        _, alone = sos_gas(QUARTIC)
    sos_gas(QUARTIC)
    [path] = entries(cache)
    path.unlink()
    os.mkfifo(path)
    writer = _Writer(path)
    try:
        _, again = sos_gas(QUARTIC)
    finally:
        opened = writer.release()
    assert not opened, "the store opened a FIFO"
    assert "stored" not in again["solver"] and again["solver"]["solves"]  # searched, as without the store
    for key in ("status", "summary", "degree", "certificate"):
        assert again[key] == alone[key], key
    assert path.is_file() and store.recall(path.stem) is not None  # the search's entry replaced the pipe


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="FIFOs are POSIX")
def test_only_a_regular_file_of_bounded_size_is_an_entry(cache: Path) -> None:
    cache.mkdir(parents=True)
    key = "0" * 32
    path = cache / f"{key}.json"
    good = json.dumps({"key": key, "found": {}})
    target = cache / "target.json"
    target.write_text(good)
    path.symlink_to(target)  # a symlink to a regular file is read
    assert store.recall(key) == {"key": key, "found": {}}
    path.unlink()
    fifo = cache / "pipe"
    os.mkfifo(fifo)
    writer = _Writer(fifo)
    path.symlink_to(fifo)  # a symlink to a FIFO is not opened
    try:
        assert store.recall(key) is None
    finally:
        assert not writer.release(), "the store opened a FIFO"
    path.unlink()
    path.symlink_to(cache)  # nor a directory
    assert store.recall(key) is None
    path.unlink()
    padded = good[:-1] + " " * store.MAX_ENTRY_BYTES + "}"  # valid JSON, larger than the cap
    path.write_text(padded)
    assert store.recall(key) is None
    path.write_text(good)
    assert store.recall(key) == {"key": key, "found": {}}


def test_an_entrys_own_margin_and_solve_count_are_not_shown(cache: Path) -> None:
    """The entry's ``margin`` and ``solves`` are not re-proved by the exact check: an edited one
    reaches neither the document nor the terminal, and the certificate is still used."""
    _, first = sos_gas(QUARTIC)
    [path] = entries(cache)
    entry = json.loads(path.read_text())
    entry["found"]["margin"] = 987654.25
    entry["solves"] = 424242
    path.write_text(json.dumps(entry))
    doc, second = sos_gas(QUARTIC)
    assert "stored" in second["solver"] and second["certificate"] == first["certificate"]
    text = json.dumps(doc)
    assert "987654" not in text and "424242" not in text
    assert second["relative_margin"] is None
    done = CliRunner().invoke(app.cli, ["certify", str(QUARTIC), "--classes", "sos_gas"])
    assert done.exit_code == 0, done.output
    assert "987654" not in done.output and "424242" not in done.output and "9.877e+05" not in done.output
    [(_, said)] = solvers({"sos_gas": second})
    assert "424242" not in said
