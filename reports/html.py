"""HTML rendering: a Jinja2 environment with autoescaping, and the page's embedded images.

Autoescaping is on for every template, so each string taken from an input file (a label, a
summary, a TOML value) reaches the page as text, never as markup. The only markup not written
in the templates themselves is none at all: images enter as ``data:`` URIs (in ``src``
attributes and in the page's own stylesheet), which the browser treats as images, never as
part of the document.

- Figures are matplotlib SVGs in base64 URIs (:func:`svg_uri`); :mod:`reports.pdf` reads them
  back from there for the PDF.
- Equations are packed onto a few shared *sheets* (:class:`MathImages`). Typst writes each
  equation as a standalone SVG that carries its own copy of every glyph outline it uses: the
  114 equations of the paper's certificate report used 157 distinct outlines but carried
  1952 copies, 3.5 MB of a 3.8 MB page. On a sheet each outline is defined once. A sheet is one
  SVG data URI in the stylesheet; each equation stays an ``<img class="math">`` (alt text,
  Typst source for the PDF, size) that shows its own cell of a sheet as a CSS background.
  Everything stays vector: nothing is rasterised.
"""

from __future__ import annotations

import base64
import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterable, Sequence
from urllib.parse import quote

if TYPE_CHECKING:
    from reports.typeset import Typeset

TEMPLATES = Path(__file__).resolve().parent / "templates"
#: CSS px per typographic point
PX_PER_PT = 4 / 3
#: decimals kept in equation coordinates (pt): 0.001 pt is far below a device pixel
COORD_DIGITS = 3
#: the largest sheet, CSS px (a sheet is as wide as its widest equation where that is wider).
#: Why a limit: a browser may rasterise a whole background image at the device's resolution; at
#: 3 device pixels per CSS px a 960 px square costs about 33 MB, while a page's equations on a
#: single sheet could cost several times that on a phone. The price is a few outlines repeated.
SHEET_WIDTH_PX = 960
SHEET_HEIGHT_PX = 960
#: empty space around each equation on a sheet, CSS px: browsers snap background offsets to
#: device pixels, so a neighbour must be more than a pixel away never to show at an edge
SHEET_GAP_PX = 6
#: characters left as they are in a ``data:image/svg+xml,`` URI. Everything else is
#: percent-encoded, in particular ``"``, ``&``, ``<``, ``>`` and ``\``, so such a URI is inert
#: in a double-quoted HTML attribute and in a double-quoted CSS ``url()``; ``#`` and ``%`` must be
#: encoded in any URI. Spaces and ``'`` stay: browsers read them in ``src`` and ``url("")``, and
#: percent-encoding them (or base64) would cost 10 to 33 % more bytes.
URI_SAFE = " '()*+,-./:;=?@[]_!~$"

_SVG = "{http://www.w3.org/2000/svg}"
_XLINK_HREF = "{http://www.w3.org/1999/xlink}href"
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_FLIPPED = re.compile(rf"matrix\(1 0 0 -1 ({_NUMBER}) ({_NUMBER})\)")
_TRANSLATE = re.compile(rf"translate\(({_NUMBER}) ({_NUMBER})\)")
_VIEWBOX = re.compile(rf"0 0 ({_NUMBER}) ({_NUMBER})")
# no arcs (A): their flags may be written without separators, which this tokeniser cannot read
_PATH_TOKEN = re.compile(rf"[MmLlHhVvCcSsQqTtZz]|{_NUMBER}")
_PATH_DATA = re.compile(rf"(?:[\s,]|[MmLlHhVvCcSsQqTtZz]|{_NUMBER})*")
#: presentation attributes of Typst's stroked rules (fraction bars, roots) and their defaults
_STROKE_DEFAULTS = {"fill": None, "stroke": None, "stroke-width": None, "stroke-linecap": "butt",
                    "stroke-linejoin": "miter", "stroke-miterlimit": "4", "stroke-opacity": None}
_STROKE_VALUE = re.compile(rf"#[0-9A-Fa-f]{{3,8}}|none|[a-z]+|{_NUMBER}")
#: a transparent image with an equation's proportions: the ``src`` of an equation on a sheet
_PLACEHOLDER = "<svg xmlns='http://www.w3.org/2000/svg' viewBox='0 0 {w} {h}'/>"


def svg_uri(svg: bytes) -> str:
    """``data:image/svg+xml;base64,...`` for an SVG document (the figures: see the module docstring)."""
    return "data:image/svg+xml;base64," + base64.b64encode(svg).decode("ascii")


def svg_text_uri(svg: str) -> str:
    """A percent-encoded ``data:image/svg+xml,`` URI, as :class:`markupsafe.Markup`.

    Marked safe so that autoescaping does not turn each ``'`` into ``&#39;``: the URI holds no
    character that could end an attribute or a CSS string (see :data:`URI_SAFE`).
    """
    import markupsafe

    return markupsafe.Markup("data:image/svg+xml," + quote(svg, safe=URI_SAFE))


def _px(pt: float) -> str:
    return f"{pt * PX_PER_PT:.1f}"


def _num(x: float) -> str:
    """A coordinate, short: :data:`COORD_DIGITS` decimals at most, no trailing or leading zeros."""
    text = f"{x:.{COORD_DIGITS}f}".rstrip("0").rstrip(".")
    if text in ("", "-0"):
        return "0"
    if text.startswith("0."):
        return text[1:]
    if text.startswith("-0."):
        return "-" + text[2:]
    return text


#: numbers each path command takes (one segment; a command letter may be followed by several)
_ARITY = {"m": 2, "l": 2, "h": 1, "v": 1, "c": 6, "s": 4, "q": 4, "t": 2, "z": 0}


def compact_path_data(d: str) -> str:
    """SVG path data written short, drawing the same path to :data:`COORD_DIGITS` decimals.

    Rounding is done on absolute positions, and a relative step is written as the difference of
    two rounded positions: rounding each relative number on its own would let the error grow
    along the path (Typst writes scaled glyphs, e.g. superscripts, with 4 decimals). A separator
    is kept only where it is needed: a sign, a command letter or a second decimal point already
    ends a number (``1.5.5`` reads as 1.5 and 0.5). Data that is not a well-formed sequence of
    the commands in :data:`_ARITY` is returned unchanged.
    """
    tokens = _PATH_TOKEN.findall(d)
    out: list[str] = []
    prev = ""

    def emit(text: str) -> None:
        nonlocal prev
        if not text.isalpha() and prev and not prev.isalpha() \
                and not text.startswith("-") and not (text.startswith(".") and "." in prev):
            out.append(" ")
        out.append(text)
        prev = text

    def rounded(v: float) -> float:
        return round(v, COORD_DIGITS)

    # exact and rounded current point, and the same for the start of the subpath
    cur, cur_r, start, start_r = (0.0, 0.0), (0.0, 0.0), (0.0, 0.0), (0.0, 0.0)
    i, command = 0, ""
    while i < len(tokens):
        if tokens[i].isalpha():
            command = tokens[i]
            emit(command)
            i += 1
            if command in "Zz":
                cur, cur_r = start, start_r
                continue
        n = _ARITY.get(command.lower(), -1)
        if n <= 0 or i + n > len(tokens) or any(t.isalpha() for t in tokens[i:i + n]):
            return d
        values = [float(t) for t in tokens[i:i + n]]
        i += n
        relative = command.islower()
        kind = command.lower()
        # the segment's points, absolute and exact; which coordinate each number is
        axes = "x" if kind == "h" else "y" if kind == "v" else "xy" * (n // 2)
        base = cur if relative else (0.0, 0.0)
        exact = [base[0] + v if a == "x" else base[1] + v for v, a in zip(values, axes)]
        base_r = cur_r if relative else (0.0, 0.0)
        for v, a in zip(exact, axes):
            r = rounded(v)
            emit(_num(r - (base_r[0] if a == "x" else base_r[1])))
        end_x = exact[-2] if kind not in "hv" else (exact[-1] if kind == "h" else cur[0])
        end_y = exact[-1] if kind not in "hv" else (exact[-1] if kind == "v" else cur[1])
        cur, cur_r = (end_x, end_y), (rounded(end_x), rounded(end_y))
        if kind == "m":
            start, start_r = cur, cur_r
            command = "l" if relative else "L"  # further pairs after a moveto are line-tos
    return "".join(out)


# ----------------------------------------------------------------------------------------------
# equations: Typst SVG -> what it draws -> sheets
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Drawing:
    """What one Typst equation draws, in its own page's coordinates (pt, y down).

    ``glyphs``: ``(outline path data, x, y)``, each outline drawn y-up from the origin ``(x, y)``
    (font coordinates, as Typst places them); ``rules``: ``(attributes, path data, x, y)``,
    stroked paths translated to ``(x, y)``, attributes already written as SVG.
    """

    width: float
    height: float
    glyphs: tuple[tuple[str, float, float], ...]
    rules: tuple[tuple[str, str, float, float], ...]


def _local(el: ET.Element) -> str | None:
    return el.tag[len(_SVG):] if el.tag.startswith(_SVG) else None


def _glyph_run(el: ET.Element, outlines: dict[str, str], out: list[tuple[str, float, float]]) -> bool:
    """``<g transform="matrix(1 0 0 -1 X Y)">`` of black ``<use>`` glyphs (Typst's text runs)."""
    found = _FLIPPED.fullmatch(el.get("transform", ""))
    if found is None or set(el.attrib) != {"transform"}:
        return False
    x0, y0 = float(found.group(1)), float(found.group(2))
    for use in el:
        attrs = dict(use.attrib)
        href = attrs.pop(_XLINK_HREF, None) or attrs.pop("href", None)
        colour, rule = attrs.pop("fill", "#000000"), attrs.pop("fill-rule", "nonzero")
        try:
            x, y = float(attrs.pop("x", 0.0)), float(attrs.pop("y", 0.0))
        except ValueError:
            return False
        if _local(use) != "use" or len(use) or attrs or colour != "#000000" or rule != "nonzero" \
                or href is None or not href.startswith("#") or href[1:] not in outlines:
            return False
        # the use's own (x, y) is in the flipped system: down the page is y0 - y
        out.append((outlines[href[1:]], x0 + x, y0 - y))
    return True


def _rule(el: ET.Element) -> tuple[str, str, float, float] | None:
    """A stroked ``<path>`` (fraction bar, root, matrix line); None if it is anything else."""
    attrs = dict(el.attrib)
    d = attrs.pop("d", "")
    found = _TRANSLATE.fullmatch(attrs.pop("transform", "translate(0 0)"))
    if len(el) or found is None or not _PATH_DATA.fullmatch(d) or not set(attrs) <= set(_STROKE_DEFAULTS):
        return None
    if not all(_STROKE_VALUE.fullmatch(v) for v in attrs.values()):
        return None
    kept = "".join(f" {k}='{v}'" for k, v in attrs.items() if v != _STROKE_DEFAULTS[k])
    return kept, compact_path_data(d), float(found.group(1)), float(found.group(2))


def parse_typst_svg(svg: bytes) -> Drawing | None:
    """What a Typst equation SVG draws, or None for anything but the structure Typst writes.

    Typst (0.1x) writes glyph runs (:func:`_glyph_run`), stroked rules (:func:`_rule`) and a
    ``<defs>`` of one-path ``<symbol>`` outlines. Any other element, attribute or value gives
    None, and the equation is then shown from its own, untouched SVG: a future Typst that
    writes something new costs bytes, never a wrong picture.
    """
    try:
        root = ET.fromstring(svg)
    except ET.ParseError:
        return None
    size = _VIEWBOX.fullmatch(root.get("viewBox", ""))
    if _local(root) != "svg" or size is None:
        return None
    outlines: dict[str, str] = {}
    for defs in (el for el in root if _local(el) == "defs"):
        for symbol in defs:
            path = symbol[0] if len(symbol) == 1 else None
            if _local(symbol) != "symbol" or path is None or _local(path) != "path" or set(path.attrib) != {"d"} \
                    or not set(symbol.attrib) <= {"id", "overflow"} or not _PATH_DATA.fullmatch(path.get("d", "")):
                return None
            outlines[symbol.get("id", "")] = compact_path_data(path.get("d", ""))
    glyphs: list[tuple[str, float, float]] = []
    rules: list[tuple[str, str, float, float]] = []
    for el in root:
        tag = _local(el)
        if tag == "defs":
            continue
        if tag == "g" and _glyph_run(el, outlines, glyphs):
            continue
        rule = _rule(el) if tag == "path" else None
        if rule is None:
            return None
        rules.append(rule)
    return Drawing(float(size.group(1)), float(size.group(2)), tuple(glyphs), tuple(rules))


def _short_id(n: int) -> str:
    """``a``, ``b``, ..., ``z``, ``aa``, ``ab``, ...: the n-th outline's id on a sheet."""
    letters = "abcdefghijklmnopqrstuvwxyz"
    text = ""
    while True:
        text = letters[n % 26] + text
        n = n // 26 - 1
        if n < 0:
            return text


def sheet_svg(placed: Sequence[tuple[Drawing, float, float]], width: float, height: float) -> str:
    """One SVG drawing each ``(drawing, x, y)`` with its top left corner at ``(x, y)``.

    Each glyph outline is defined once; every glyph is a ``<use>`` of it inside one flipped
    group (``y`` negated), so its coordinates are plain numbers. ``preserveAspectRatio="none"``
    because the page stretches a sheet exactly onto the size it asks for (see :class:`MathImages`).
    """
    ids: dict[str, str] = {}
    uses: list[str] = []
    rules: list[str] = []
    for drawing, ox, oy in placed:
        for outline, x, y in drawing.glyphs:
            ref = ids.setdefault(outline, _short_id(len(ids)))
            uses.append(f"<use href='#{ref}' x='{_num(ox + x)}' y='{_num(-(oy + y))}'/>")
        for attrs, d, x, y in drawing.rules:
            rules.append(f"<path{attrs} transform='translate({_num(ox + x)} {_num(oy + y)})' d='{d}'/>")
    defs = "".join(f"<path id='{ref}' d='{outline}'/>" for outline, ref in ids.items())
    return (f"<svg xmlns='http://www.w3.org/2000/svg' viewBox='0 0 {_num(width)} {_num(height)}' "
            f"preserveAspectRatio='none'><defs>{defs}</defs><g transform='scale(1 -1)'>{''.join(uses)}</g>"
            f"{''.join(rules)}</svg>")


def pack(boxes: Sequence[tuple[float, float]]) -> list[tuple[list[tuple[int, int, int]], int, int]]:
    """Shelf-pack boxes (CSS px), in page order, onto sheets.

    Returns ``(placements, width, height)`` per sheet, a placement being ``(index into boxes,
    x, y)``. Offsets are whole CSS px, so that a browser's snapping of background offsets to
    pixels moves no equation: it is drawn with the same pixel alignment as a standalone image.
    Page order keeps the equations a reader sees together on the same sheet.
    """
    width = max([SHEET_WIDTH_PX] + [math.ceil(w) for w, _ in boxes])
    sheets: list[tuple[list[tuple[int, int, int]], int, int]] = []
    placed: list[tuple[int, int, int]] = []
    x = y = shelf = 0  # the next free place on the current shelf, and the shelf's height
    for k, (w, h) in enumerate(boxes):
        if placed and x + w > width:
            x, y, shelf = 0, y + shelf + SHEET_GAP_PX, 0
        if placed and y + h > SHEET_HEIGHT_PX:
            sheets.append((placed, width, max(py + math.ceil(boxes[i][1]) for i, _, py in placed)))
            placed, x, y, shelf = [], 0, 0, 0
        placed.append((k, x, y))
        x += math.ceil(w) + SHEET_GAP_PX
        shelf = max(shelf, math.ceil(h))
    if placed:
        sheets.append((placed, width, y + shelf))
    return sheets


@dataclass(frozen=True)
class MathImage:
    """How the page shows one equation: the ``<img>``'s class, ``src`` and ``style``."""

    cls: str
    src: str
    style: str


def _percent(x: float) -> str:
    # 5 decimals: an error of 1e-7 of a sheet (under 1000 px) is far below a pixel
    return f"{x:.5f}".rstrip("0").rstrip(".") + "%"


class MathImages:
    """The equations of one page, on shared sheets (module docstring); each shown by :meth:`image`.

    An equation on a sheet is an ``<img>`` with a transparent placeholder ``src`` of its own
    proportions and its cell of the sheet as background. Sizes and offsets are percentages of
    the image itself, so the cell stays in register at any zoom, or when print CSS shrinks the
    image to the column. An equation that is not on a sheet (not passed in, or an SVG
    :func:`parse_typst_svg` does not know) gets a ``src`` of its own.
    """

    def __init__(self, typesets: Iterable[Typeset] = ()) -> None:
        unique = list(dict.fromkeys(typesets))
        self._drawings = {t: parse_typst_svg(t.svg) for t in unique}
        # a cell is exactly the <img> box the template writes (width/height attributes), so the
        # sheet's scale on the page is exactly PX_PER_PT and whole-px offsets stay whole; an
        # empty box (a size Typst's header did not give) could not be placed by percentages
        on_sheets = [t for t in unique if self._drawings[t] is not None and min(self._box(t)) > 0]
        boxes = [self._box(t) for t in on_sheets]
        self._cells: dict[Typeset, tuple[int, int, int, int, int]] = {}
        self._sheets: list[str] = []
        for k, (placed, width, height) in enumerate(pack(boxes)):
            drawings = [(self._drawings[on_sheets[i]], x / PX_PER_PT, y / PX_PER_PT) for i, x, y in placed]
            self._sheets.append(sheet_svg([(d, x, y) for d, x, y in drawings if d is not None],
                                          width / PX_PER_PT, height / PX_PER_PT))
            self._cells.update({on_sheets[i]: (k, x, y, width, height) for i, x, y in placed})

    @staticmethod
    def _box(typeset: Typeset) -> tuple[float, float]:
        return float(_px(typeset.width_pt)), float(_px(typeset.height_pt))

    @property
    def sheet_count(self) -> int:
        return len(self._sheets)

    def css(self) -> Any:
        """Stylesheet rules: one background per sheet (URIs inert in CSS, see :data:`URI_SAFE`)."""
        import markupsafe

        if not self._sheets:
            return markupsafe.Markup("")
        rules = ["img.math.on-sheet { background-repeat: no-repeat; }"]
        rules += [f'img.math.sheet-{k} {{ background-image: url("{svg_text_uri(svg)}"); }}'
                  for k, svg in enumerate(self._sheets)]
        return markupsafe.Markup("\n".join(rules))

    def image(self, typeset: Typeset) -> MathImage:
        """The class, ``src`` and ``style`` of the ``<img>`` that shows ``typeset``."""
        cell = self._cells.get(typeset)
        if cell is None:
            drawing = self._drawings[typeset] if typeset in self._drawings else parse_typst_svg(typeset.svg)
            if drawing is None:
                return MathImage("math", svg_uri(typeset.svg), "")
            return MathImage("math", svg_text_uri(sheet_svg([(drawing, 0.0, 0.0)], drawing.width, drawing.height)), "")
        k, x, y, width, height = cell
        w, h = self._box(typeset)
        # background-position p% puts the sheet's p% point on the box's p% point: the offset is
        # (box - sheet) * p, which is -x for p = x / (sheet - box), at any scale of the box
        px = x / (width - w) * 100 if width > w else 0.0
        py = y / (height - h) * 100 if height > h else 0.0
        style = (f"background-size:{_percent(width / w * 100)} {_percent(height / h * 100)};"
                 f"background-position:{_percent(px)} {_percent(py)}")
        placeholder = _PLACEHOLDER.format(w=_num(typeset.width_pt), h=_num(typeset.height_pt))
        return MathImage(f"math on-sheet sheet-{k}", svg_text_uri(placeholder), style)


# ----------------------------------------------------------------------------------------------
# the environment
# ----------------------------------------------------------------------------------------------
@lru_cache(maxsize=1)
def environment() -> Any:
    """The Jinja2 environment (templates in ``reports/templates``, autoescape always on)."""
    import jinja2
    import markupsafe

    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(TEMPLATES)),
        autoescape=True,  # every template, whatever its extension
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters["svg_uri"] = svg_uri
    env.filters["px"] = _px
    # our own stylesheet, not input: inserted as is (escaping would break its quotes)
    env.globals["css"] = markupsafe.Markup((TEMPLATES / "report.css").read_text(encoding="utf-8"))
    return env


def render_html(template: str, context: dict[str, Any]) -> str:
    """Render ``template`` (a file in ``reports/templates``) with ``context``.

    ``context["equations"]``, when present, lists the page's typeset equations
    (:class:`reports.typeset.Typeset`): they are put on shared sheets (:class:`MathImages`).
    """
    images = MathImages(context.get("equations", ()))
    return str(environment().get_template(template).render(**context, math_images=images))
