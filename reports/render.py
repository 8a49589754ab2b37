"""Public entry points: a certificate or a sweep store -> HTML and/or PDF files.

The PDF is the HTML page translated into Typst and compiled (:mod:`reports.pdf`), so both
formats always carry the same content; see ``reports/README.md`` for the choice.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Final

from lyapcheck.errors import InputFileError, InvalidParameter, LyapcheckError
from lyapcheck.fileio import atomic_write

log = logging.getLogger(__name__)

FORMATS = (".html", ".pdf")


def _check_format(path: str | Path) -> str:
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise InvalidParameter("report", "a file name ending in .html or .pdf", str(path))
    return suffix


def html_to_pdf(html: str) -> bytes:
    """The PDF of a report page (:mod:`reports.pdf`: the page translated to Typst)."""
    from reports.pdf import html_to_pdf as typst_pdf

    return typst_pdf(html)


def write_page(html: str, path: str | Path) -> Path:
    """Write a rendered page as HTML or PDF, chosen by the file extension."""
    if _check_format(path) == ".pdf":
        return atomic_write(path, html_to_pdf(html))
    return atomic_write(path, html.encode("utf-8"))


@dataclass(frozen=True)
class PageKind:
    """One kind of report page: which input it shows, how its context is built, its template.

    ``accepts`` sees the input (a certificate document, or a loaded sweep store); ``context``
    builds the page's data (``**options`` are the keywords of :func:`certificate_html`, which a
    store's page does not take).
    """

    name: str
    accepts: Callable[[Any], bool]
    context: Callable[..., dict[str, Any]]
    template: str


def _certificate_context(doc: dict[str, Any], **options: Any) -> dict[str, Any]:
    from reports.certificate_page import certificate_context

    return certificate_context(doc, **options)


def _is_model_store(ds: Any) -> bool:
    from sweeps.schema import is_model_dataset

    return bool(is_model_dataset(ds))


def _is_box_store(ds: Any) -> bool:
    from sweeps.schema import is_box_dataset

    return bool(is_box_dataset(ds))


def _model_store_context(ds: Any) -> dict[str, Any]:
    from reports.stores.model_file import model_store_context

    return model_store_context(ds)


def _box_store_context(ds: Any) -> dict[str, Any]:
    from reports.stores.paper_boxes import box_context

    return box_context(ds)


def _grid_store_context(ds: Any) -> dict[str, Any]:
    from reports.stores.paper_grid import sweep_context

    return sweep_context(ds)


#: the pages a report can be, tried in order: the first that accepts its input renders it. Every
#: certificate, the paper's or a model file's, is one page (reports.certificate_page), which takes
#: the subject of its model from the document's kind (reports.subjects); a sweep store's page
#: depends on its schema (reports.stores).
CERTIFICATE_PAGES: Final = (
    PageKind("certificate", lambda doc: isinstance(doc, dict), _certificate_context, "certificate.html.j2"),
)
STORE_PAGES: Final = (
    PageKind("model sweep store", _is_model_store, _model_store_context, "model_sweep.html.j2"),
    PageKind("paper box store", _is_box_store, _box_store_context, "boxes.html.j2"),
    PageKind("paper sweep store", lambda ds: True, _grid_store_context, "sweep.html.j2"),
)


def page_kind(value: Any, kinds: tuple[PageKind, ...]) -> PageKind:
    """The first page kind of ``kinds`` that accepts ``value``."""
    for kind in kinds:
        if kind.accepts(value):
            return kind
    raise InputFileError("a certificate must be a JSON object")


def certificate_html(doc: dict[str, Any], *, ledger: bool = True, simulate: bool = True, recheck: bool = True) -> str:
    """The certificate report (any model's) as one self-contained HTML page."""
    from reports.html import render_html

    kind = page_kind(doc, CERTIFICATE_PAGES)
    return render_html(kind.template, kind.context(doc, ledger=ledger, simulate=simulate, recheck=recheck))


def certificate_report(doc: dict[str, Any], path: str | Path) -> Path:
    """Write the report of a certificate document to ``path`` (``.html`` or ``.pdf``).

    This is what ``lyapcheck certify --report FILE`` calls.
    """
    _check_format(path)
    return write_page(certificate_html(doc), path)


def read_store(path: str | Path) -> Any:
    """A sweep store, loaded and checked against :mod:`sweeps.schema` (one-line errors if it is not one).

    The data chunks are decoded when the store is loaded, so a truncated or edited chunk (a
    codec error, a JSON error, a missing key) surfaces here, where it is a bad input file.
    """
    from reports.stores.common import open_store
    from sweeps.schema import check_dataset, check_model_dataset, is_model_dataset

    try:
        dataset = open_store(path)
    except LyapcheckError:
        raise
    except Exception as exc:  # noqa: BLE001 - zarr and its codecs raise many types for a corrupt store
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputFileError(f"'{path}' is not a readable sweep store (Zarr): {first}") from None
    if is_model_dataset(dataset):  # a model file's sweep (sweeps.schema)
        check_model_dataset(dataset, str(path))
    else:
        check_dataset(dataset, str(path))
    return dataset


def sweep_html(store: Any) -> str:
    """The sweep report as one self-contained HTML page (``store``: a path or an xarray Dataset)."""
    from reports.html import render_html

    dataset = read_store(store) if isinstance(store, (str, Path)) else store
    kind = page_kind(dataset, STORE_PAGES)
    return render_html(kind.template, kind.context(dataset))


def sweep_report(store: Any, path: str | Path) -> Path:
    """Write the report of a sweep store (path to a Zarr store, or a Dataset) to ``path``."""
    _check_format(path)
    return write_page(sweep_html(store), path)


def is_sweep_store(path: str | Path) -> bool:
    """A Zarr store is a directory (or ends in ``.zarr``); a certificate is a JSON file."""
    p = Path(path)
    return p.is_dir() or p.suffix.lower() == ".zarr"


def report_files(source: str | Path, html: str | Path | None, pdf: str | Path | None) -> list[Path]:
    """The ``lyapcheck report`` command: read a certificate or a sweep store, write the outputs.

    With neither ``html`` nor ``pdf``, writes ``<source stem>.html`` in the current directory.
    """
    from reports.certificate_page import read_certificate

    for name, value, suffix in (("html", html, ".html"), ("pdf", pdf, ".pdf")):
        if value is not None and Path(value).suffix.lower() != suffix:
            raise InvalidParameter(name, f"a file name ending in {suffix}", str(value))
    src = Path(source)
    if not src.exists():
        raise InputFileError(f"input file '{src}' does not exist")
    if html is None and pdf is None:
        name = src.resolve().name  # "." and ".." name their directory
        if not name or name in (".", ".."):
            raise InvalidParameter("html", f"given: '{source}' has no name to call the report after", None)
        html = Path(name).with_suffix(".html")
    if is_sweep_store(src):
        page = sweep_html(src)
    else:
        page = certificate_html(read_certificate(src))
    written = []
    if html is not None:
        written.append(write_page(page, html))
    if pdf is not None:
        written.append(write_page(page, pdf))
    return written


__all__ = ["PageKind", "CERTIFICATE_PAGES", "STORE_PAGES", "page_kind", "certificate_report", "certificate_html", "sweep_report", "sweep_html", "read_store", "report_files",
           "html_to_pdf", "write_page"]
