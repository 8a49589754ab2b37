"""PDF output: the report's HTML page, translated element by element into Typst, compiled offline.

Why translate the HTML instead of keeping a second template: the PDF then carries exactly the
content of the HTML page by construction. Why Typst instead of an HTML-to-PDF engine: the
mathematics is typeset natively from the same Typst source that produced the page's SVG
equations (vector glyphs, real fonts), the compiler ships in a wheel with its fonts (no TeX,
no browser, no system library), and a 40-page report compiles in about a second.

The translator knows the small HTML vocabulary of ``reports/templates`` (headings, paragraphs,
tables, lists, code, badges, boxes, figures, equations); an unknown element contributes its
text. Every piece of text reaches Typst as a string literal (``#"...";``), so nothing taken from
an input can act as Typst markup or code. Equations are ``img.math`` elements whose
``data-typst`` attribute holds the Typst source written by :mod:`reports.typeset`; figures are
``data:`` SVG images, written next to the document for Typst to read.
"""

from __future__ import annotations

import base64
import re
import tempfile
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path
from typing import Final

#: elements whose content is laid out as blocks (the others are inline)
_BLOCKS: Final = {"html", "body", "header", "footer", "section", "nav", "div", "p", "h1", "h2", "h3", "h4",
                  "table", "thead", "tbody", "tr", "ul", "ol", "li", "pre", "figure", "figcaption"}
_VOID: Final = {"img", "br", "meta", "link", "hr", "input"}
_SKIP: Final = {"head", "style", "script", "title"}
#: the page's status colours (report.css)
COLOURS: Final = {
    "certified": "#1a7f37", "holds": "#1a7f37", "refuted": "#cf222e", "fails": "#cf222e",
    "discrepancy": "#cf222e", "not_certified": "#9a6700", "unverifiable": "#9a6700", "inconclusive": "#8250df",
    "counterexample": "#cf222e",
    # the tones of a page's head (reports.subjects.base.verdict_tone, answer_lines)
    "tone-ok": "#1a7f37", "tone-bad": "#cf222e", "tone-warn": "#9a6700", "tone-plain": "#6e7781",
}
#: the verdict box's fill per tone (report.css, .verdict.tone-*)
VERDICT_FILLS: Final = {"tone-ok": "#dafbe1", "tone-warn": "#fff8c5", "tone-bad": "#ffebe9"}
_NEUTRAL: Final = "#6e7781"
#: unbroken runs longer than this (exact rationals, hashes) get a break opportunity (a
#: zero-width space) every _BREAK_EVERY characters; shorter words stay intact for search
_BREAK_RUN: Final = 40
_BREAK_EVERY: Final = 20

PREAMBLE: Final = """\
#set document(title: {title})
#set page(paper: "a4", margin: (x: 15mm, top: 15mm, bottom: 18mm),
  footer: context [#set text(size: 7.5pt, fill: rgb("#59636e")); #{title} #h(1fr) page #counter(page).display("1 of 1", both: true)])
#set text(font: "Libertinus Serif", size: 10.5pt, lang: "en")
#set par(justify: false, leading: 0.6em, spacing: 0.9em)
#show raw: set text(font: "DejaVu Sans Mono", size: 0.85em)
#show heading: set block(above: 1.3em, below: 0.6em)
#show heading.where(level: 1): set text(size: 18pt)
#show heading.where(level: 2): it => block(width: 100%, stroke: (bottom: 1.2pt + rgb("#d1d9e0")), inset: (bottom: 3pt), text(size: 14pt, it.body))
#show heading.where(level: 3): set text(size: 11.5pt)
#show heading.where(level: 4): set text(size: 10pt, fill: rgb("#59636e"))
#set table(stroke: (x: none, y: 0.5pt + rgb("#d1d9e0")), inset: (x: 4pt, y: 3.5pt))
#show table: set text(size: 9pt)
// equations wider than the column are scaled down to fit it (the HTML scrolls them instead)
#let fit(body) = layout(size => {
  let m = measure(body)
  if m.width > size.width { let f = size.width / m.width * 100%; scale(x: f, y: f, reflow: true, body) } else { body }
})
#let badge(colour, body) = box(fill: rgb(colour), inset: (x: 3pt, y: 1.2pt), outset: (y: 1pt), radius: 5pt,
  text(fill: white, weight: "bold", size: 0.8em, body))
"""


@dataclass
class Node:
    """An element of the parsed page (text nodes have ``tag == "#text"``)."""

    tag: str
    attrs: dict[str, str] = field(default_factory=dict)
    children: list["Node"] = field(default_factory=list)
    text: str = ""

    @property
    def classes(self) -> set[str]:
        return set(self.attrs.get("class", "").split())


class _TreeBuilder(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.root = Node("root")
        self.stack = [self.root]
        self.skip = 0

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag in _SKIP:
            self.skip += 1
            return
        node = Node(tag, {k: v or "" for k, v in attrs})
        self.stack[-1].children.append(node)
        if tag not in _VOID:
            self.stack.append(node)

    def handle_startendtag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.handle_starttag(tag, attrs)
        if tag not in _VOID and tag not in _SKIP:
            self.stack.pop()

    def handle_endtag(self, tag: str) -> None:
        if tag in _SKIP:
            self.skip = max(0, self.skip - 1)
            return
        for i in range(len(self.stack) - 1, 0, -1):  # tolerate unclosed elements
            if self.stack[i].tag == tag:
                del self.stack[i:]
                break

    def handle_data(self, data: str) -> None:
        if not self.skip:
            self.stack[-1].children.append(Node("#text", text=data))


def parse(html: str) -> Node:
    builder = _TreeBuilder()
    builder.feed(html)
    builder.close()
    return builder.root


def literal(text: str) -> str:
    """A Typst string literal in markup, terminated (``#"...";``): shown verbatim, never parsed."""
    escaped = text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n").replace("\r", "")
    return f'#"{escaped}";'


def _breakable(text: str) -> str:
    """Insert break opportunities into long unbroken runs (exact rationals, hashes)."""
    def split(m: re.Match[str]) -> str:
        word = m.group(0)
        return "\u200b".join(word[i:i + _BREAK_EVERY] for i in range(0, len(word), _BREAK_EVERY))

    return re.sub(r"\S{%d,}" % (_BREAK_RUN + 1), split, text)


class _Translator:
    def __init__(self, assets: Path) -> None:
        self.assets = assets
        self.figures = 0

    # -- inline content --------------------------------------------------------------------------
    def text_of(self, node: Node) -> str:
        if node.tag == "#text":
            return node.text
        return "".join(self.text_of(c) for c in node.children)

    def inline(self, node: Node) -> str:
        if node.tag == "#text":
            text = re.sub(r"\s+", " ", node.text)
            return literal(text) if text else ""
        tag, cls = node.tag, node.classes
        if tag == "br":
            return "#linebreak();"
        if tag == "img":
            return self.image(node)
        if tag == "code":
            text = re.sub(r"\s+", " ", self.text_of(node))
            if "exact" in cls:
                return ("#block(breakable: true, text(font: \"DejaVu Sans Mono\", size: 7.5pt, fill: rgb(\"#59636e\"))["
                        + literal(_breakable(text)) + "])")
            return "#text(font: \"DejaVu Sans Mono\", size: 0.85em)[" + literal(_breakable(text)) + "]"
        if tag == "span" and "word" in cls:
            return f"#text(size: 17pt, weight: \"bold\")[{self.inlines(node)}]"
        if tag == "span" and "badge" in cls:
            status = next((c for c in cls if c != "badge"), "")
            colour = COLOURS.get(status, _NEUTRAL)
            return f'#badge("{colour}")[{self.inlines(node)}]'
        body = self.inlines(node)
        if tag in ("strong", "b"):
            return f"#strong[{body}]"
        if tag in ("em", "i"):
            return f"#emph[{body}]"
        if tag == "sub":
            return f"#sub[{body}]"
        if tag == "sup":
            return f"#super[{body}]"
        if tag in _BLOCKS:
            return self.block(node)
        return body

    def inlines(self, node: Node) -> str:
        return "".join(self.inline(c) for c in node.children)

    def image(self, node: Node) -> str:
        if "math" in node.classes and node.attrs.get("data-typst"):
            return f"#box(fit(math.equation(block: true, ${node.attrs['data-typst']}$)))"
        src = node.attrs.get("src", "")
        prefix = "data:image/svg+xml;base64,"
        if src.startswith(prefix):
            self.figures += 1
            name = f"figure-{self.figures}.svg"
            (self.assets / name).write_bytes(base64.b64decode(src[len(prefix):]))
            return f'#image("{name}", width: 100%)'
        return literal(f"[image: {node.attrs.get('alt', '')}]")

    # -- blocks ----------------------------------------------------------------------------------
    def blocks(self, node: Node) -> str:
        out: list[str] = []
        run: list[Node] = []

        def flush() -> None:
            text = "".join(self.inline(n) for n in run).strip()
            if text and text not in ('#" ";',):
                out.append(text)
            run.clear()

        for child in node.children:
            if child.tag in _BLOCKS and child.tag not in ("#text",):
                flush()
                out.append(self.block(child))
            else:
                run.append(child)
        flush()
        return "\n\n".join(o for o in out if o)

    def block(self, node: Node) -> str:
        tag, cls = node.tag, node.classes
        if tag in ("h1", "h2", "h3", "h4"):
            return f"#heading(level: {tag[1]})[{self.inlines(node).strip()}]"
        if tag == "pre":
            return "#block(fill: rgb(\"#f6f8fa\"), inset: 6pt, radius: 3pt, width: 100%, text(font: \"DejaVu Sans Mono\", size: 8pt)[" \
                   + "#linebreak();".join(literal(_breakable(line)) for line in self.text_of(node).strip("\n").split("\n")) \
                   + "])"
        if tag == "table":
            return self.table(node)
        if tag in ("ul", "ol"):
            items = [c for c in node.children if c.tag == "li"]
            fn = "list" if tag == "ul" else "enum"
            return f"#{fn}(" + ", ".join(f"[{self.blocks(i)}]" for i in items) + ")"
        if tag == "figure":
            return "#block(breakable: false, width: 100%)[" + self.blocks(node) + "]"
        if tag == "figcaption":
            return "#text(size: 8.5pt, fill: rgb(\"#59636e\"))[" + self.inlines(node).strip() + "]"
        body = self.blocks(node)
        status = next((c for c in cls if c in COLOURS), None)
        colour = COLOURS.get(status or "", _NEUTRAL)
        if "page-break" in cls:
            body = "#pagebreak(weak: true)\n" + body
        if "verdict" in cls:
            # the box's colour is its tone, never the verdict's word (an unknown tone is neutral)
            tone = next((c for c in sorted(cls) if c in VERDICT_FILLS), "")
            colour, fill = COLOURS.get(tone, _NEUTRAL), VERDICT_FILLS.get(tone, "#f6f8fa")
            return f'#block(width: 100%, inset: 8pt, radius: 5pt, stroke: 2pt + rgb("{colour}"), fill: rgb("{fill}"))[{body}]'
        if "alarm" in cls:
            return f'#block(width: 100%, inset: 7pt, radius: 4pt, stroke: 2pt + rgb("#cf222e"), fill: rgb("#ffebe9"))[#strong[{body}]]'
        if "condition" in cls:
            return f'#block(width: 100%, inset: (left: 8pt, rest: 5pt), stroke: (left: 4pt + rgb("{colour}"), rest: 0.5pt + rgb("#d1d9e0")))[{body}]'
        if "card" in cls:
            return (f'#block(width: 100%, breakable: false, inset: (left: 7pt, rest: 5pt), '
                    f'stroke: (left: 3pt + rgb("{colour}"), rest: 0.5pt + rgb("#d1d9e0")))[{body}]')
        if "group" in cls:
            return f'#block(width: 100%, inset: (left: 7pt), stroke: (left: 1pt + rgb("#d1d9e0")))[{body}]'
        if "note" in cls or "muted" in cls or "form-name" in cls:
            return f'#text(size: 8.5pt, fill: rgb("#59636e"))[{body}]'
        if "head" in cls:
            return "#strong[" + " #h(0.6em) ".join(self.inline(c) for c in node.children if c.tag != "#text") + "]"
        if tag == "p":
            return body
        return body

    def table(self, node: Node) -> str:
        rows: list[tuple[bool, list[Node]]] = []

        def collect(n: Node, head: bool) -> None:
            for c in n.children:
                if c.tag == "tr":
                    rows.append((head, [d for d in c.children if d.tag in ("td", "th")]))
                elif c.tag in ("thead", "tbody", "tfoot"):
                    collect(c, c.tag == "thead")

        collect(node, False)
        if not rows:
            return ""
        ncols = max(len(cells) for _, cells in rows)
        kv = "kv" in node.classes and ncols == 2
        columns = "(38%, 1fr)" if kv else f"{ncols}"
        cells: list[str] = []
        for head, row in rows:
            for cell in row + [Node("td")] * (ncols - len(row)):
                body = self.blocks(cell).strip()
                cells.append(f"[#strong[{body}]]" if head else f"[{body}]")
        header = ""
        if rows[0][0]:
            header = "table.header(" + ", ".join(cells[:ncols]) + "), "
            cells = cells[ncols:]
        return f"#table(columns: {columns}, {header}" + ", ".join(cells) + ")"


def html_to_typst(html: str, assets: Path) -> str:
    """Typst source of a report page (figures written into ``assets``)."""
    root = parse(html)
    translator = _Translator(assets)
    title = "lyapcheck report"
    for node in _walk(root):
        if node.tag == "h1":
            title = re.sub(r"\s+", " ", translator.text_of(node)).strip()
            break
    body = translator.blocks(root)
    return PREAMBLE.replace("{title}", f'"{_quote(title)}"') + "\n" + body + "\n"


def _quote(text: str) -> str:
    return text.replace("\\", "\\\\").replace('"', '\\"')


def _walk(node: Node) -> list[Node]:
    out = [node]
    for c in node.children:
        out.extend(_walk(c))
    return out


def html_to_pdf(html: str) -> bytes:
    """Compile a report page to PDF with Typst (offline, fonts from the typst wheel)."""
    import typst

    from lyapcheck.errors import LyapcheckError

    with tempfile.TemporaryDirectory(prefix="lyapcheck-report-") as tmp:
        root = Path(tmp)
        source = html_to_typst(html, root)
        (root / "report.typ").write_text(source, encoding="utf-8")
        try:
            pdf = typst.compile(str(root / "report.typ"), root=str(root), format="pdf", ignore_system_fonts=True)
        except typst.TypstError as exc:
            raise LyapcheckError(f"the PDF could not be typeset: {exc}") from None
    return bytes(pdf)  # type: ignore[arg-type]
