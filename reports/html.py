"""HTML rendering: a Jinja2 environment with autoescaping, and data-URI embedding.

Autoescaping is on for every template, so each string taken from an input file (a label, a
summary, a TOML value) reaches the page as text, never as markup. The only markup not written
in the templates themselves is none at all: SVGs (equations, figures) enter as base64 data URIs
in ``src`` attributes, which the browser treats as images, never as part of the document.
"""

from __future__ import annotations

import base64
from functools import lru_cache
from pathlib import Path
from typing import Any

TEMPLATES = Path(__file__).resolve().parent / "templates"
#: CSS px per typographic point
PX_PER_PT = 4 / 3


def svg_uri(svg: bytes) -> str:
    """``data:image/svg+xml;base64,...`` for an SVG document."""
    return "data:image/svg+xml;base64," + base64.b64encode(svg).decode("ascii")


def _px(pt: float) -> str:
    return f"{pt * PX_PER_PT:.1f}"


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
    """Render ``template`` (a file in ``reports/templates``) with ``context``."""
    return str(environment().get_template(template).render(**context))
