"""One reader of a JSON input file (:func:`lyapcheck.fileio.read_json`), used by the model and the paper
certificates alike: every way a file can be unreadable is one line naming the file, and both readers say
it in the same words."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import pytest

from lyapcheck.errors import InputFileError
from lyapcheck.fileio import read_json


def _write(name: str, text: str | bytes) -> Callable[[Path], Path]:
    def make(d: Path) -> Path:
        p = d / name
        p.write_bytes(text if isinstance(text, bytes) else text.encode())
        return p

    return make


CASES = [
    (lambda d: d / "absent.json", "does not exist"),
    (_write("bad.json", "{not json"), "is not valid JSON"),
    (_write("latin.json", b'{"a": "\xe9"}'), "is not valid JSON"),
    (_write("deep.json", "[" * 100_000 + "]" * 100_000), "is nested too deeply to be read"),
    (_write("huge.json", "1" * 5000), "cannot be read"),
    (lambda d: (d / "dir.json").mkdir() or d / "dir.json", "cannot be read"),
]


@pytest.mark.parametrize("make, message", CASES)
def test_every_unreadable_file_is_one_line_naming_it(tmp_path: Path, make: Any, message: str) -> None:
    from lyapcheck.models.surfaces.certificate import read_json as read_model
    from lyapcheck.paper.certificate import read_document as read_paper

    path = make(tmp_path)
    for read in (read_json, read_model, read_paper):
        with pytest.raises(InputFileError) as info:
            read(path)
        text = str(info.value)
        assert message in text and f"'{path}'" in text and len(text.splitlines()) == 1


def test_a_readable_file_is_its_value(tmp_path: Path) -> None:
    path = tmp_path / "ok.json"
    path.write_text('{"kind": "x", "values": [1, 2.5, "3/4"]}')
    assert read_json(path) == {"kind": "x", "values": [1, 2.5, "3/4"]}
