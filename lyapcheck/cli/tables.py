"""Result tables for the terminal: every cell whole at any width.

A number cut in a table cell misleads (``8.78182e…`` reads as 8.78), so no cell here is ever cut
inside a word, at any console width. :func:`print_table` computes the column widths itself
(rich's own collapse may shrink a column below its longest word and then fold or ellipsize it):

1. every column gets at least its longest word (a number is one word) and at most its longest
   line; text wraps at spaces only;
2. when the columns do not fit side by side, the table is split into several, each repeating the
   key columns (the row's name);
3. when not even the key and one more column fit, each row is printed as a record: its key, then
   one ``header: value`` line per column, wrapped at spaces (a word longer than the console is
   printed whole and left to the terminal).

The command modules (:mod:`lyapcheck.cli.certify`, :mod:`lyapcheck.cli.simulate`) call the
renderers at the bottom with their ``--json`` document and a console; tests pass a
``Console(width=..., file=StringIO())``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal, Mapping, Sequence

if TYPE_CHECKING:  # pragma: no cover
    from rich.console import Console
    from rich.text import Text

#: colour of each status (DESIGN.md's statuses)
STATUS_STYLE: Mapping[str, str] = {
    "certified": "bold green", "refuted": "bold red", "not_certified": "yellow", "inconclusive": "magenta",
    "holds": "green", "fails": "red", "not_applicable": "dim", "counterexample": "bold red",
}
#: a column of prose ("what it means") is not made narrower than this: below it the next layout is used
PROSE_MIN_WIDTH = 24
#: the summary column of the conditions: below this width the status and property go under the name
SUMMARY_MIN_WIDTH = 32
#: a table with n columns takes 3 n + 1 characters besides its cells (borders and one space of padding)
BORDER_PER_COLUMN, BORDER_EXTRA = 3, 1
#: the figure format of simulated quantities (six significant digits, as the JSON rounds nothing)
FIGURE_FORMAT = ".6g"


@dataclass(frozen=True)
class Column:
    """One column: its header, alignment, style and the narrowest width its text may wrap to."""

    header: str
    justify: Literal["left", "right", "center"] = "left"
    style: str | None = None
    min_width: int = 0


def _text(cell: "str | Text") -> "Text":
    from rich.text import Text

    return cell if isinstance(cell, Text) else Text(str(cell))


def _widths(cells: Sequence["Text"]) -> tuple[int, int]:
    """(longest word, longest line) over the cells, in terminal cells."""
    from rich.cells import cell_len

    word = line = 0
    for cell in cells:
        for text_line in cell.plain.splitlines() or [""]:
            line = max(line, cell_len(text_line))
            word = max([word, *(cell_len(w) for w in text_line.split())])
    return word, line


def fit_widths(columns: Sequence[Column], rows: Sequence[Sequence["Text"]], width: int) -> list[int] | None:
    """Column widths (cells only) for a table of ``width`` characters, or None if it cannot hold
    every column at its longest word (and prose at :attr:`Column.min_width`)."""
    available = width - BORDER_PER_COLUMN * len(columns) - BORDER_EXTRA
    low, high = [], []
    for k, col in enumerate(columns):
        word, line = _widths([_text(col.header), *(row[k] for row in rows)])
        low.append(max(word, min(col.min_width, line), 1))
        high.append(max(line, low[-1]))
    if sum(low) > available:
        return None
    widths = list(low)
    spare = available - sum(widths)
    # give the spare width to the columns that want more, the most wanting first, one at a time
    # (a prose column takes what the short ones leave)
    while spare > 0:
        wanting = [k for k in range(len(widths)) if widths[k] < high[k]]
        if not wanting:
            break
        k = max(wanting, key=lambda i: high[i] - widths[i])
        step = min(spare, high[k] - widths[k], max(1, spare // len(wanting)))
        widths[k] += step
        spare -= step
    return widths


def _table(title: "str | Text | None", columns: Sequence[Column], rows: Sequence[Sequence["Text"]],
           widths: Sequence[int], show_lines: bool) -> Any:
    from rich.table import Table

    table = Table(title=title, show_lines=show_lines)
    for col, w in zip(columns, widths):
        table.add_column(_text(col.header), justify=col.justify, style=col.style, width=w, overflow="fold")
    for row in rows:
        table.add_row(*row)
    return table


def print_table(console: "Console", title: "str | Text | None", columns: Sequence[Column],
                rows: Sequence[Sequence["str | Text"]], *, keys: int = 1, show_lines: bool = False) -> None:
    """Print ``rows`` under ``columns``: one table if it fits, else several repeating the first
    ``keys`` columns, else one record per row (see the module's docstring)."""
    cells = [[_text(c) for c in row] for row in rows]
    width = console.width
    whole = fit_widths(columns, cells, width)
    if whole is not None:
        console.print(_table(title, columns, cells, whole, show_lines))
        return
    key_cols, rest = list(range(keys)), list(range(keys, len(columns)))
    parts: list[list[int]] = []
    for k in rest:
        trial = (parts[-1] if parts else []) + [k]
        if parts and fit_widths([columns[i] for i in key_cols + trial], [[r[i] for i in key_cols + trial]
                                                                         for r in cells], width) is not None:
            parts[-1] = trial
        elif fit_widths([columns[i] for i in key_cols + [k]], [[r[i] for i in key_cols + [k]] for r in cells],
                        width) is not None:
            parts.append([k])
        else:
            print_records(console, title, columns, cells, keys)
            return
    for n, part in enumerate(parts):
        chosen = key_cols + part
        sub_cols = [columns[i] for i in chosen]
        sub_rows = [[r[i] for i in chosen] for r in cells]
        widths = fit_widths(sub_cols, sub_rows, width)
        assert widths is not None  # checked while the parts were built
        label = title if n == 0 else None
        if n == 0 and len(parts) > 1 and title is not None:
            label = _text(title).copy()
            label.append(f" ({len(parts)} tables)")
        console.print(_table(label, sub_cols, sub_rows, widths, show_lines))


def print_records(console: "Console", title: "str | Text | None", columns: Sequence[Column],
                   rows: Sequence[Sequence["Text"]], keys: int) -> None:
    """One record per row: the key cells on a line, then ``header: value`` lines, wrapped at spaces."""
    from rich.text import Text

    if title is not None:
        say(console, _text(title))
    for row in rows:
        head = Text(" ").join(row[:keys])
        head.stylize("bold")
        say(console, head)
        for col, cell in zip(columns[keys:], row[keys:]):
            if not cell.plain:
                continue
            line = Text("  ")
            line.append(f"{col.header}: ", style="dim")
            line.append_text(cell)
            say(console, line)


def say(console: "Console", text: "str | Text") -> None:
    """Print text wrapped at spaces to the console's width; a word longer than the console stays
    whole on its own line (the terminal wraps it) instead of being folded or cut."""
    for line in wrap_words(_text(text), console.width):
        console.print(line, soft_wrap=True)


def wrap_words(text: "Text", width: int) -> list["Text"]:
    """``text`` in lines of at most ``width`` cells, broken at spaces only; a line's leading spaces
    indent its continuation lines too (a word that fits the width only without them goes unindented)."""
    import re

    from rich.cells import cell_len
    from rich.text import Text

    lines = []
    for para in text.split("\n"):
        words = [(m.start(), m.end()) for m in re.finditer(r"\S+", para.plain)]
        if not words:
            lines.append(para)
            continue
        indent = para.plain[:words[0][0]]

        def lead(s: int, e: int) -> str:
            return indent if cell_len(indent + para.plain[s:e]) <= width else ""

        start, end, prefix = 0, words[0][1], ""
        for s, e in words[1:]:
            if cell_len(prefix + para.plain[start:e]) <= width:
                end = e
                continue
            lines.append(Text(prefix) + para[start:end])
            start, end = s, e
            prefix = lead(s, e)
        lines.append(Text(prefix) + para[start:end])
    return lines


def figure(x: Any) -> str:
    """A simulated figure with six significant digits; ``-`` for none (a diverged set)."""
    return "-" if x is None else format(x, FIGURE_FORMAT)


# -- certify ---------------------------------------------------------------------------------------

def what_it_means(doc: Mapping[str, Any], cond: Mapping[str, Any]) -> str:
    """A condition's summary and, for a certified V, its short form (the first terms to six
    significant digits; the exact V is in the JSON): ``V = ...``, one line per output for
    ``sos_bound``."""
    from lyapcheck.models.classes.claims import V_SHORT_TERMS, size_words, v_text

    text = str(cond["summary"])
    cert = cond.get("certificate")
    if cond.get("status") != "certified" or not isinstance(cert, Mapping):
        return text
    size = size_words(cond)
    if size:
        text += f"\n{size}"
    shifts = doc.get("equilibrium") if isinstance(doc.get("equilibrium"), Mapping) else {}
    parts = [("V", cert)] if "V_text" in cert else []
    outputs = cert.get("outputs")
    if isinstance(outputs, Mapping):
        parts += [(f"V_{name}", data) for name, data in outputs.items() if isinstance(data, Mapping) and "V_text" in data]
    for label, data in parts:
        try:
            names, at = data["variables"], shifts
            if data.get("kind") in ("recast", "lyapunov_relations"):  # a loop with functions: each auxiliary by its definition
                names = [data["auxiliaries"].get(n, n) for n in data["variables"]]
                at = {data["auxiliaries"].get(n, n): v for n, v in data["shift"].items()}
            text += f"\n{label} = {v_text(data['V'], names, at, limit=V_SHORT_TERMS)}"
        except (KeyError, TypeError, ValueError, ArithmeticError):
            continue  # a malformed V is verify's to report; the table shows the summary alone
    return text


#: the keys of a condition whose text is for the curious (solver statuses, limits, counts): shown
#: with ``--verbose`` only
DETAIL_KEYS = ("detail", "reason")


def print_conditions(console: "Console", doc: Mapping[str, Any], verbose: bool = False) -> None:
    """The conditions of a certificate document (``certify --json``): one row per class with its
    status, property and summary; at narrow widths the status and property go under the name. With
    ``verbose``, each condition's technical detail (:data:`DETAIL_KEYS`) follows its summary."""
    from rich.text import Text

    title = (f"lyapcheck certify - model: {doc['model']['name']}" if "model" in doc
             else f"lyapcheck certify - dynamics: {doc['dynamics']}")
    if "model" in doc and isinstance(doc.get("box"), dict) and doc["box"]:
        from lyapcheck.models.classes.claims import box_words

        title += f", for every {box_words(doc['box'])}"
    conditions = {name: {**c, "summary": what_it_means(doc, c) + (_details(c) if verbose else "")}
                  for name, c in doc["conditions"].items()}

    def status(cond: Mapping[str, Any]) -> Text:
        return Text(str(cond["status"]), style=STATUS_STYLE.get(str(cond["status"]), ""))

    wide_cols = [Column("condition", style="cyan"), Column("status"), Column("property"),
                 Column("what it means", min_width=SUMMARY_MIN_WIDTH)]
    wide = [[Text(name), status(c), Text(str(c.get("property", ""))), Text(str(c["summary"]))]
            for name, c in conditions.items()]
    if fit_widths(wide_cols, wide, console.width) is not None:
        print_table(console, Text(title), wide_cols, wide, show_lines=True)
        return
    narrow_cols = [Column("condition"), Column("what it means", min_width=PROSE_MIN_WIDTH)]
    narrow = []
    for name, c in conditions.items():
        head = Text(name, style="cyan")
        head.append("\n").append_text(status(c))
        if c.get("property"):
            head.append("\n" + str(c["property"]))
        narrow.append([head, Text(str(c["summary"]))])
    if fit_widths(narrow_cols, narrow, console.width) is not None:
        print_table(console, Text(title), narrow_cols, narrow, show_lines=True)
    else:
        print_records(console, Text(title), wide_cols, wide, keys=3)


def _details(cond: Mapping[str, Any]) -> str:
    out = ""
    for key in DETAIL_KEYS:
        value = cond.get(key)
        if isinstance(value, str) and value and value not in str(cond.get("summary", "")):
            out += f"\n[{key}] {value}"
        elif isinstance(value, list):
            out += "".join(f"\n[{key}] {v}" for v in value)
    return out


#: colour of each answer (lyapcheck.answers): a negative one is red, an undecided one yellow
ANSWER_STYLE: Mapping[str, str] = {
    "global": "bold green", "region": "green", "local": "yellow", "safe": "bold green", "proved": "bold green",
    "bounded": "green", "undecided": "yellow", "unstable": "bold red", "unsafe": "bold red", "fails": "bold red",
}


def print_answers(console: "Console", doc: Mapping[str, Any], unmet: Sequence[str] = ()) -> None:
    """The headline: one line per question asked (``answers``), then the verdict and what it means,
    then the ``--require`` names not met."""
    from rich.text import Text

    from lyapcheck.answers import VERDICT_MEANING

    stated = doc.get("answers")
    answers: Mapping[str, Any] = stated if isinstance(stated, Mapping) else {}
    for question, a in answers.items():
        if isinstance(a, Mapping):
            say(console, Text.assemble((f"{question.replace('_', '-')}: ", "bold"),
                                       (str(a.get("answer", "")), ANSWER_STYLE.get(str(a.get("answer")), "")),
                                       f" - {a.get('text', '')}"))
    verdict = str(doc.get("verdict"))
    style = {"certified": "bold green", "unsafe": "bold red", "unstable": "bold red"}.get(verdict, "bold yellow")
    say(console, Text.assemble("verdict: ", (verdict, style), f"  ({VERDICT_MEANING.get(verdict, '')})"))
    if unmet:
        say(console, Text.assemble(("required but not proved: ", "bold red"), ", ".join(unmet)))


# -- simulate ----------------------------------------------------------------------------------------

def print_model_simulation(console: "Console", doc: Mapping[str, Any]) -> None:
    """``simulate --model``: per scenario the trajectories, converged, diverged and the tail sup of
    every output; with many outputs, the counts and the sups (one row per output) in two tables."""
    from rich.text import Text

    outputs = list(doc["outputs"])
    w0, w1 = doc["tail_window_s"]
    title = Text(f"lyapcheck simulate --model: {doc['model']['name']} (tail window {w0:.4g}-{w1:.4g} s)")
    scenarios = dict(doc["scenarios"])
    names = [*scenarios, "all"]
    totals = {"trajectories": doc["n_trajectories"], "converged": doc["n_converged"],
              "diverged": doc["n_diverged"], "sup_abs_output_tail": doc["sup_abs_output_tail"]}
    per = {**scenarios, "all": totals}

    def name_cell(name: str) -> Text:
        return Text(name, style="bold" if name == "all" else "")

    def diverged(n: int) -> Text:
        return Text(str(n), style="bold red" if n else "")

    counts_cols = [Column("scenario"), Column("trajectories", "right"), Column("converged", "right"),
                   Column("diverged", "right")]
    counts = [[name_cell(s), Text(str(per[s]["trajectories"])), Text(str(per[s]["converged"])),
               diverged(int(per[s]["diverged"]))] for s in names]
    wide_cols = counts_cols + [Column(f"tail sup |{y}|", "right") for y in outputs]
    wide = [row + [Text(figure(per[s]["sup_abs_output_tail"][y])) for y in outputs] for row, s in zip(counts, names)]
    if fit_widths(wide_cols, wide, console.width) is not None:
        print_table(console, title, wide_cols, wide)
    else:
        print_table(console, title, counts_cols, counts)
        sup_cols = [Column("output")] + [Column(s, "right", style="bold" if s == "all" else None) for s in names]
        sups = [[Text(y)] + [Text(figure(per[s]["sup_abs_output_tail"][y])) for s in names] for y in outputs]
        print_table(console, Text(f"tail sup |y| over {w0:.4g}-{w1:.4g} s, per scenario"), sup_cols, sups)


def print_paper_simulation(console: "Console", doc: Mapping[str, Any], disturbance: str) -> None:
    """``simulate`` of the paper's loop (a preset or a scenario file): the measured quantities beside
    the paper's figures."""
    from rich.text import Text

    paper = doc.get("paper", {})

    def mm(x: float) -> str:
        return f"{x * 1e3:.4g} mm"

    def ref(key: str, fmt: Any) -> str:
        if key not in paper:
            return ""
        p = paper[key]
        return f"{fmt(p['reported'])} ({p['relative_deviation']:+.1%})"

    w0, w1 = doc["tail_window_s"]
    conv = doc["convergence_time_s"]
    rows = [
        [f"mean |eps| over {w0:g}-{w1:g} s", mm(doc["mean_abs_eps_tail_m"]), ref("mean_abs_eps_tail_m", mm)],
        [f"sup |eps| over {w0:g}-{w1:g} s", mm(doc["sup_abs_eps_tail_m"]), ""],
        [f"sup |(eps, s)| over {w0:g}-{w1:g} s", mm(doc["sup_norm_eps_s_tail_m"]), ""],
        ["final eps", mm(doc["final_eps_m"]), ""],
        ["steady rotation (mean |u| over the tail)", f"{doc['steady_rotation_hz']:.4g} Hz",
         ref("steady_rotation_hz", lambda x: f"{x:.3g} Hz")],
        ["max rotation |u| (every controller call)",
         f"{doc['max_rotation_hz']:.4g} Hz (limit {doc['omega_so_hz']:.4g} Hz)", ""],
        ["steady speed along the path", f"{doc['steady_speed_m_s'] * 1e3:.4g} mm/s",
         f"e11 alpha_d Delta = {doc['speed_star_m_s'] * 1e3:.4g} mm/s"],
        [f"convergence time to |eps| <= {mm(doc['band_m'])}", "not converged" if conv is None else f"{conv:.4g} s",
         ""],
        ["diverged", "yes" if doc["diverged"] else "no", ""],
    ]
    columns = [Column("quantity"), Column("value", "right"),
               Column("paper (deviation)" if paper else "reference", "right")]
    title = Text(f"lyapcheck simulate: {doc['scenario']} ({doc['controller']}, ODS {doc['ods_form']})")
    print_table(console, title, columns, rows)
    say(console, f"disturbance: {disturbance}")


def print_model_worst_case(console: "Console", doc: Mapping[str, Any], disturbance_text: Any) -> None:
    """``simulate --model --worst-case``: per output the worst tail sup found, the disturbance that
    gave it and, with a certificate, the certified bound and the tightness ratio."""
    from rich.text import Text

    tight = doc.get("tightness")
    columns = [Column("output"), Column("worst tail sup", "right"), Column("disturbance", min_width=PROSE_MIN_WIDTH)]
    if tight is not None:
        columns += [Column("certified bound", "right"), Column("tightness_ratio", "right")]
    rows = []
    for y, found in doc["worst"].items():
        row = [Text(y), Text(figure(found["sup_abs_output_tail"])), Text(disturbance_text(found["disturbance"]))]
        if tight is not None:
            t = tight.get(y)
            if t is None:
                row += [Text("-"), Text("-")]
            else:
                ratio = figure(t["tightness_ratio"])
                row += [Text(figure(t["certified_bound"])),
                        Text(f"{ratio} SOUNDNESS VIOLATION", style="bold red") if t["soundness_violation"]
                        else Text(ratio)]
        rows.append(row)
    print_table(console, Text(f"lyapcheck simulate --model --worst-case: {doc['model']['name']}"), columns, rows)


__all__ = ["Column", "fit_widths", "print_table", "print_records", "say", "wrap_words", "figure", "print_conditions", "print_model_simulation",
           "print_paper_simulation", "print_model_worst_case", "STATUS_STYLE"]
