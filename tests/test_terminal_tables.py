"""Result tables in the terminal: no cell is ever cut inside a word or a number, at any width.

Issue 29, item 5: at 80 columns (a pipe) ``certify --model`` cut cells mid-number (``8.78182e…``
reads as 8.78) and the 10-state ``simulate --model`` table was unreadable. Every test renders at
60, 80 and 120 columns (and narrower) and checks that every word of every cell of the JSON
document (every summary, every simulated figure) appears whole in the text, that no ellipsis is
printed, and that no line is wider than the console.
"""

from __future__ import annotations

import io
import re
from pathlib import Path
from typing import Any, Iterable

import pytest
from click.testing import CliRunner
from hypothesis import given, seed, settings
from hypothesis import strategies as st
from rich.console import Console

from lyapcheck import certify, simulate
from lyapcheck.cli import app  # type: ignore[attr-defined]
from lyapcheck.cli import tables
from lyapcheck.cli.simulate import _model_disturbance_text
from tests.conftest import PAPER_TOML, ROOT

app._register_commands()
MODELS = ROOT / "examples" / "models"
WIDTHS = (60, 80, 120)
#: below this, a word of the shipped documents may be longer than the console (then it is printed
#: whole and left to the terminal, which is checked too)
NARROW = (30, 40)


def render(printer: Any, doc: dict[str, Any], width: int, *extra: Any) -> str:
    console = Console(width=width, file=io.StringIO(), color_system=None)
    printer(console, doc, *extra)
    out = console.file.getvalue()  # type: ignore[attr-defined]
    return str(out)


def whole(word: str, text: str) -> bool:
    """``word`` appears in ``text`` with whitespace (or the text's ends) on both sides."""
    return re.search(rf"(?<!\S){re.escape(word)}(?!\S)", text) is not None


def assert_whole(text: str, cells: Iterable[str], width: int) -> None:
    assert "…" not in text, text
    words = [w for cell in cells for w in str(cell).split()]
    missing = [w for w in words if not whole(w, text)]
    assert not missing, f"cut or missing at width {width}: {missing[:5]}\n{text}"
    longest = max([len(w) for w in words] + [0])
    if longest <= width:
        assert max(len(line) for line in text.splitlines()) <= width, text


def numbers(text: str) -> list[str]:
    return re.findall(r"(?<![\w.])[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?", text)


# -- documents ------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def paper_doc() -> dict[str, Any]:
    return certify(PAPER_TOML).to_dict()


@pytest.fixture(scope="module")
def model_doc() -> dict[str, Any]:
    """A disturbed model: every summary says which disturbances it covers."""
    return certify(model=MODELS / "linear-disturbed-l1.toml").to_dict()


@pytest.fixture(scope="module")
def ten_states() -> dict[str, Any]:
    return simulate(model=MODELS / "lyznet-10d.toml", series=False).to_dict()


@pytest.fixture(scope="module")
def scenarios_doc() -> dict[str, Any]:
    """Every scenario family (none, constant, bang-bang, square), two outputs."""
    return simulate(model=MODELS / "linear-disturbed-l1.toml", series=False).to_dict()


def synthetic_certificate(n_classes: int = 6) -> dict[str, Any]:
    """Long numbers in long summaries, the statuses and properties of every width."""
    statuses = ["certified", "not_applicable", "counterexample", "inconclusive", "refuted", "holds"]
    properties = ["ultimate_bound", "invariant_set", "GES", "ROA", "LES", ""]
    conditions = {}
    for k in range(n_classes):
        summary = (f"(d = 0) limsup |y{k}| <= 8.781823456789e-05 and V' <= -1.2345678901234 V on "
                   f"{{V <= 0.99980712345}} for every mu in [4/5, 6/5]; decay exp(-0.0235{k} t) from {k + 1} starts")
        conditions[f"class_number_{k}"] = {"status": statuses[k % 6], "summary": summary,
                                           "property": properties[k % 6]}
    return {"model": {"name": "a model with a long name 1.23456789e-07 and [brackets]"}, "conditions": conditions,
            "verdict": "certified"}


# -- certify ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("width", WIDTHS + NARROW)
def test_certify_tables_keep_every_word_whole(paper_doc: dict[str, Any], model_doc: dict[str, Any],
                                              width: int) -> None:
    for doc in (paper_doc, model_doc, synthetic_certificate()):
        text = render(tables.print_conditions, doc, width)
        cells = [f"{name} {c['status']} {c.get('property', '')} {c['summary']}" for name, c in doc["conditions"].items()]
        assert_whole(text, cells, width)
        for summary in (c["summary"] for c in doc["conditions"].values()):
            for number in numbers(summary):
                assert re.search(rf"(?<![\d.]){re.escape(number)}(?!\d)", text), (number, text)


def test_certify_layouts_by_width(paper_doc: dict[str, Any]) -> None:
    """Wide: four columns; narrower: status and property under the name; narrowest: records."""
    wide = render(tables.print_conditions, paper_doc, 120)
    assert "┃ status" in wide and "┃ property" in wide
    middle = render(tables.print_conditions, paper_doc, 60)
    assert "┃ status" not in middle and "┃ what it means" in middle
    narrow = render(tables.print_conditions, paper_doc, 30)
    assert "┃" not in narrow and "what it means:" in narrow


def test_certify_command_at_80_columns_through_a_pipe(model_doc: dict[str, Any]) -> None:
    done = CliRunner().invoke(app.cli, ["certify", str(MODELS / "linear-disturbed-l1.toml")],
                              env={"COLUMNS": "80"}, catch_exceptions=False)
    assert done.exit_code == 0, done.output
    cells = [c["summary"] for c in model_doc["conditions"].values()]
    assert_whole(done.stdout, cells, 80)
    assert "verdict: certified" in done.stdout


# -- simulate ------------------------------------------------------------------------------------------

def figures_of(doc: dict[str, Any]) -> list[str]:
    out = [tables.figure(v) for v in doc["sup_abs_output_tail"].values()]
    for sc in doc["scenarios"].values():
        out += [tables.figure(v) for v in sc["sup_abs_output_tail"].values()]
    return out


@pytest.mark.parametrize("width", WIDTHS + NARROW)
def test_model_simulation_tables_keep_every_figure_whole(ten_states: dict[str, Any], scenarios_doc: dict[str, Any],
                                                         width: int) -> None:
    for doc in (ten_states, scenarios_doc):
        text = render(tables.print_model_simulation, doc, width)
        assert_whole(text, figures_of(doc) + list(doc["scenarios"]), width)
        for y in doc["outputs"]:  # a row's name, or a column's "tail sup |y|"
            assert whole(y, text) or whole(f"|{y}|", text), (y, text)
        # every count is there too, beside its scenario
        assert whole(str(doc["n_trajectories"]), text)


def test_ten_states_at_80_columns_is_one_row_per_output(ten_states: dict[str, Any]) -> None:
    text = render(tables.print_model_simulation, ten_states, 80)
    for y, v in ten_states["sup_abs_output_tail"].items():
        row = [line for line in text.splitlines() if re.match(rf"│ {re.escape(y)}\s+│", line)]
        assert len(row) == 1 and whole(tables.figure(v), row[0]), text


@pytest.mark.parametrize("width", WIDTHS)
def test_simulate_command_at_each_width(ten_states: dict[str, Any], width: int) -> None:
    done = CliRunner().invoke(app.cli, ["simulate", str(MODELS / "lyznet-10d.toml")], env={"COLUMNS": str(width)},
                              catch_exceptions=False)
    assert done.exit_code == 0, done.output
    assert_whole(done.stdout, figures_of(ten_states), width)  # the same seeded starts as the API's


@pytest.mark.parametrize("width", WIDTHS + NARROW)
def test_paper_simulation_and_worst_case_tables(width: int) -> None:
    paper = simulate(preset="paper-ilos", series=False).to_dict()
    from lyapcheck.cli.simulate import _disturbance_text

    text = render(tables.print_paper_simulation, paper, width, _disturbance_text(paper["disturbance"]))
    assert_whole(text, [f"{paper['mean_abs_eps_tail_m'] * 1e3:.4g}", f"{paper['steady_rotation_hz']:.4g}",
                        _disturbance_text(paper["disturbance"])], width)
    worst = {"model": {"name": "cascade"}, "worst": {
        "y": {"sup_abs_output_tail": 0.49999999999999994,
              "disturbance": {"kind": "square", "amplitude": {"d": 1.0}, "angular_frequency_rad_s": 0.785398,
                              "frequency_hz": 0.125, "phase_rad": 1.5707963}},
        "w": {"sup_abs_output_tail": 1.2345678e-09, "disturbance": {"kind": "constant", "d": {"d": -1.0}}}},
        "tightness": {"y": {"tightness_ratio": 1.0712345, "certified_bound": 0.5356172, "soundness_violation": False},
                      "w": {"tightness_ratio": 0.99, "certified_bound": 0.5, "soundness_violation": True}}}
    text = render(tables.print_model_worst_case, worst, width, _model_disturbance_text)
    cells = ["0.5", "1.23457e-09", "1.07123", "0.535617", "SOUNDNESS VIOLATION",
             *(_model_disturbance_text(f["disturbance"]) for f in worst["worst"].values())]
    assert_whole(text, cells, width)


# -- the layout itself, on any words at any width ------------------------------------------------------

WORD = st.one_of(st.from_regex(r"[-+]?\d{1,6}(\.\d{1,8})?(e[-+]\d{2})?", fullmatch=True),
                 st.from_regex(r"[a-z_|(){}<=>]{1,14}", fullmatch=True))


@seed(29)
@settings(max_examples=60, deadline=None)
@given(rows=st.lists(st.lists(st.lists(WORD, min_size=1, max_size=12).map(" ".join), min_size=4, max_size=4),
                     min_size=1, max_size=6),
       width=st.integers(min_value=16, max_value=160))
def test_print_table_never_cuts_a_word(rows: list[list[str]], width: int) -> None:
    columns = [tables.Column("name"), tables.Column("value", "right"), tables.Column("status"),
               tables.Column("prose", min_width=tables.PROSE_MIN_WIDTH)]
    console = Console(width=width, file=io.StringIO(), color_system=None)
    tables.print_table(console, "a title with 1.2345e-05 in it", columns, rows, show_lines=True)
    text = console.file.getvalue()  # type: ignore[attr-defined]
    assert_whole(text, [cell for row in rows for cell in row] + ["1.2345e-05"], width)


def test_wrap_words_keeps_long_words_whole_and_indents() -> None:
    from rich.text import Text

    lines = tables.wrap_words(Text("  what it means: 0.123456789012345678901234567890 and more words here"), 20)
    # the number is longer than the console: whole, on a line of its own, without the indent
    assert [line.plain for line in lines] == ["  what it means:", "0.123456789012345678901234567890",
                                              "  and more words", "  here"]


def test_a_summary_with_brackets_is_not_read_as_markup(tmp_path: Path) -> None:
    doc = synthetic_certificate(1)
    doc["conditions"]["class_number_0"]["summary"] = "needs a [domain] and [bold]x[/bold] stays literal"
    text = render(tables.print_conditions, doc, 100)
    assert "[domain]" in text and "[bold]x[/bold]" in text
