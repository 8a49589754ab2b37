"""A number written with a huge decimal exponent never stalls a reader of a document.

``"1e999999999"`` is eleven characters whose exact value has a billion digits: building it as a
:class:`~fractions.Fraction` takes minutes and gigabytes. ``verify`` reads certificates that
anyone may have edited, so every number of a document is bounded before any is read
(:func:`lyapcheck.exact.refuse_oversized_numbers`), and the one reader of a document's rationals,
:func:`lyapcheck.exact.read_rational`, refuses such a text itself.

Each certificate here is forged once per kind of numeric field it holds (the same field of every
row of a matrix counts once): every forgery must be refused as malformed, naming the field.
"""

from __future__ import annotations

import copy
import json
import re
from fractions import Fraction
from pathlib import Path
from typing import Any, Iterator

import pytest
from click.testing import CliRunner

from lyapcheck.errors import CertificateError, InputFileError
from lyapcheck.exact import oversized_number, read_rational
from lyapcheck.tolerances import MAX_READ_EXPONENT

ROOT = Path(__file__).resolve().parents[1]
HUGE = "1e999999999"
NUMBER = re.compile(r"^-?\d+(\.\d+)?([eE][+-]?\d+)?(/\d+)?$")


@pytest.mark.parametrize("text, value", [("3", Fraction(3)), ("-7/2", Fraction(-7, 2)), ("0.125", Fraction(1, 8)),
                                         ("1e-7", Fraction(1, 10**7)), (" 1/3 ", Fraction(1, 3)),
                                         (f"1e{MAX_READ_EXPONENT}", Fraction(10**MAX_READ_EXPONENT)),
                                         (0.1, Fraction(1, 10)), (2, Fraction(2))])
def test_read_rational_reads_what_fraction_reads(text: Any, value: Fraction) -> None:
    assert read_rational(text) == value


@pytest.mark.parametrize("text", [HUGE, "-1E-99999999999", f"1e{MAX_READ_EXPONENT + 1}", "1e" + "9" * 5000,
                                  "1e9_999_999", True, float("nan"), "abc", "1/0", None, [1]])
def test_read_rational_refuses_naming_the_key(text: Any) -> None:
    with pytest.raises(ValueError, match="^level: "):
        read_rational(text, "level")


def test_oversized_number_names_the_place() -> None:
    doc = {"a": ["1", {"b": "2.5e3"}], "c": {"d": ["x", f" 3{HUGE[1:]} "]}, "text": "a = 1e-7 * x"}
    assert oversized_number(doc) == "c.d[1]"
    assert oversized_number({"k": "2e0000000000000400"}) is None  # (an exponent of 400)
    # only a whole number is read as one: a model's text, a sentence, a hash are not
    assert oversized_number({"ok": ["1e-300", 1e300, "9.3e-5 m", f"x = {HUGE}", "3e99999999a7"]}) is None


def _numeric_fields(doc: Any, path: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """One path per kind of numeric field (list indices folded), outside the model's own text."""
    seen: set[tuple[Any, ...]] = set()
    stack: list[tuple[Any, tuple[Any, ...]]] = [(doc, path)]
    while stack:
        node, where = stack.pop()
        if isinstance(node, dict):
            stack.extend((v, where + (k,)) for k, v in node.items() if where or k not in ("model", "versions"))
        elif isinstance(node, list):
            stack.extend((v, where + (i,)) for i, v in enumerate(node))
        elif not isinstance(node, bool) and (isinstance(node, (int, float)) or
                                             (isinstance(node, str) and NUMBER.match(node))):
            kind = tuple("*" if isinstance(p, int) else p for p in where)
            if kind not in seen:
                seen.add(kind)
                yield where


def _certificate(tmp_path_factory: pytest.TempPathFactory, args: list[str]) -> dict[str, Any]:
    from lyapcheck.cli import app

    app._register_commands()
    out = tmp_path_factory.mktemp("cert") / "c.json"
    result = CliRunner().invoke(app.cli, ["certify", *args, "--out", str(out)])
    assert result.exit_code in (0, 1), result.output
    return json.loads(out.read_text())


@pytest.fixture(scope="module")
def documents(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, Any]]:
    models = ROOT / "examples" / "models"
    return {
        "polynomial": _certificate(tmp_path_factory, [str(models / "damped-oscillator-units.toml"), "--classes",
                                                      "linearization,quadratic,sos_bound"]),
        "functions": _certificate(tmp_path_factory, [str(models / "recast-pendulum.toml"), "--classes",
                                                     "linearization,sos_gas"]),
        "paper": _certificate(tmp_path_factory, [str(ROOT / "examples" / "paper.toml"), "--classes", "quick"]),
    }


@pytest.mark.parametrize("kind", ["polynomial", "functions", "paper"])
def test_every_forged_number_is_refused_before_it_is_read(documents: dict[str, dict[str, Any]], kind: str) -> None:
    from lyapcheck.api import verify

    doc = documents[kind]
    assert verify(doc).valid  # the honest document passes
    fields = list(_numeric_fields(doc))
    assert len(fields) > 10  # (a certificate with its matrices and figures)
    for path in fields:
        forged = copy.deepcopy(doc)
        node = forged
        for p in path[:-1]:
            node = node[p]
        node[path[-1]] = HUGE
        with pytest.raises(CertificateError, match="exponent beyond") as raised:
            verify(forged)
        assert ".".join(str(p) for p in path if not isinstance(p, int)).split(".")[-1] in str(raised.value)


def test_a_certificate_file_with_an_oversized_number_fails_in_one_line(documents: dict[str, dict[str, Any]],
                                                                 tmp_path: Path) -> None:
    from lyapcheck.cli import app

    forged = copy.deepcopy(documents["functions"])
    forged["conditions"]["linearization"]["certificate"]["P"][0][1] = HUGE
    path = tmp_path / "forged.json"
    path.write_text(json.dumps(forged))
    app._register_commands()
    result = CliRunner().invoke(app.cli, ["verify", str(path)])
    assert result.exit_code == 1, result.output  # (a certificate that fails its check: exit 1, one line)
    assert "conditions.linearization.certificate.P[0][1]" in result.output
    assert len(result.output.strip().splitlines()) == 1
    with pytest.raises((CertificateError, InputFileError)):
        from lyapcheck.models.surfaces.certificate import read_json

        read_json(path)
