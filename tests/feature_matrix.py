"""The feature matrix of issue 41: every class x loop kind x surface, exercised through the public command
line and API, each cell either supported or refused for a documented reason.

A cell is **supported** when the surface ran and gave a well-formed answer: a status of the documented
set (``not_certified`` or ``inconclusive`` count: the surface works), a certificate ``verify`` accepts, a
report that has the class's section, a sweep store with the class's status at every point or box. It is
**refused** when the surface says no in one line (exit 2, a one-line :class:`~lyapcheck.errors.LyapcheckError`)
or answers ``not_applicable`` with its reason (but ``roa``'s "the region of attraction is the whole state
space", where ``quadratic`` or ``sos_gas`` proved GAS in the same run, is an answer: :data:`ANSWERS`; a
sweep stores no summary, and its ``not_applicable`` is that answer: its ``roa`` runs beside ``quadratic`` and
``sos_gas``, and a class a sweep does not take is refused by its spec). A surface fed by a refused one (``verify`` or ``report`` of a
certificate ``certify`` did not write, ``repr`` of an API call that was refused) carries that refusal.
Anything else (a traceback, exit 3, a status outside the documented set) is a crash: :class:`Crash`.

:data:`REFUSALS` is the table of refused cells, each with the words the refusal must say and the reason in
one sentence; ``tests/test_feature_matrix.py`` fails when a cell is refused without an entry, and when an
entry's cell has become supported. ``python -m tests.feature_matrix --write`` regenerates the table of
``docs/model-files.md`` ("Feature parity") between :data:`BEGIN` and :data:`END` (``--check`` compares).

The loops are 2-state spirals, one per kind, each with a parameter ``a`` (for ``--box`` and the sweeps),
a ``[domain]`` and ``[sets]``, certified in about a second a class. ``box`` is the polynomial loop with
``--box a=0.8..1.2`` on every surface that takes a box (its sweeps are the polynomial loop's, over the
same interval, and ``simulate`` runs a point of the box, ``--set a=1.2``).
"""

from __future__ import annotations

import json
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

KINDS = ("polynomial", "rational", "functions", "disturbances", "box", "discrete", "map_functions")
CLASSES = ("linearization", "quadratic", "sos_gas", "roa", "candidate", "sos_bound", "barrier", "reach_avoid")
CLASS_SURFACES = ("certify", "verify", "--box", "sweep points", "sweep boxes", "report", "API result", "repr")
LOOP_SURFACES = ("simulate", "simulate --plot", "series", "repr")

#: statuses a model file's condition may have (docs/model-files.md, "Statuses"; DESIGN.md)
STATUSES = ("certified", "refuted", "not_certified", "inconclusive", "not_applicable", "counterexample")

#: the box of every ``--box`` cell, the interval of every sweep, the point simulated for ``box``
BOX = "a=0.8..1.2"
BOX_POINT = "a=1.2"
CANDIDATE = "x1**2 + x2**2"
#: generous: outcomes are decided by each class's work budgets, the limit is a safety net only
TIME_LIMIT_S = 600

_SETS = """
[domain]
x1 = [-3, 3]
x2 = [-3, 3]
[sets]
initial = ["(x1 - 2)**2 + x2**2 <= 0.25"]
unsafe = ["(x1 + 1)**2 + (x2 - 2)**2 <= 0.25"]
"""
_GOAL = 'goal = ["x1**2 + x2**2 <= 0.25"]\n'

POLYNOMIAL = """[model]
name = "a damped spiral with a cubic damping"
states = ["x1", "x2"]
[parameters]
a = 1
[dynamics]
x1 = "-a*x1 + x2"
x2 = "-x1 - a*x2 - x2**3"
""" + _SETS + _GOAL

RATIONAL = """[model]
name = "a damped spiral with a rational damping"
states = ["x1", "x2"]
[parameters]
a = 1
[dynamics]
x1 = "-a*x1 + x2"
x2 = "-x1 - a*x2 - x2/(1 + x1**2)"
""" + _SETS + _GOAL

FUNCTIONS = """[model]
name = "two units coupled through a sine and a saturation"
states = ["x1", "x2"]
[parameters]
a = 1
[dynamics]
x1 = "-a*x1 + sin(x2)/2"
x2 = "-x2 + sat(x1, 1)/2"
""" + _SETS + _GOAL

#: the invariant discs of V = x1**2 + x2**2 (examples/models/disturbed-tube.toml): |z|' <= -a |z| + |d|
DISTURBANCES = """[model]
name = "a damped spiral pushed by a bounded disturbance"
states = ["x1", "x2"]
[parameters]
a = 1
[disturbances]
d = 0.1
[dynamics]
x1 = "-a*x1 + x2 + d"
x2 = "-x1 - a*x2"
[domain]
x1 = [-3, 3]
x2 = [-3, 3]
[sets]
initial = ["(x1 - 1)**2 + x2**2 <= 0.01"]
unsafe = ["1.25 <= x1"]
goal = ["x1**2 + x2**2 <= 0.25"]
"""

#: a discrete-time map (issue 44): Jacobian eigenvalues a/2 +- i/4, modulus < 1 at a = 1
DISCRETE = """[model]
name = "a contracting rotation with a cubic term, a discrete-time map"
states = ["x1", "x2"]
time = "discrete"
[parameters]
a = 1
[dynamics]
x1 = "a*x1/2 + x2/4"
x2 = "-x1/4 + a*x2/2 - x2**3/8"
""" + _SETS + _GOAL

#: a discrete-time map with functions (issue 44): Jacobian [[1/2, 1/4], [-1/4, a/2]] at the fixed point 0
MAP_FUNCTIONS = """[model]
name = "a contracting rotation through a sine and a tanh, a discrete-time map"
states = ["x1", "x2"]
time = "discrete"
[parameters]
a = 1
[dynamics]
x1 = "x1/2 + sin(x2)/4"
x2 = "-x1/4 + a*tanh(x2)/2"
""" + _SETS + _GOAL

MODELS: Mapping[str, str] = {"polynomial": POLYNOMIAL, "rational": RATIONAL, "functions": FUNCTIONS,
                             "disturbances": DISTURBANCES, "box": POLYNOMIAL, "discrete": DISCRETE,
                             "map_functions": MAP_FUNCTIONS}

#: the point sweeps' and box sweeps' specs (the class list and the model file's name are filled in, and the user's V,
#: ``candidate = "..."``, where the class list has ``candidate``)
POINTS_SPEC = """[sweep]
model = "{model}"
classes = {classes}
{candidate}chunk_size = 2
[[sweep.axes]]
name = "a"
values = [0.8, 1.2]
[simulation]
starts = 2
"""
BOXES_SPEC = """[sweep]
model = "{model}"
mode = "boxes"
classes = {classes}
{candidate}chunk_size = 1
[[sweep.axes]]
name = "a"
start = 0.8
stop = 1.2
num = 2
[sweep.boxes]
max_boxes = 1
cross_check_points = 1
[simulation]
starts = 2
"""


#: a ``not_applicable`` that answers the question (``roa`` once ``quadratic`` or ``sos_gas`` proved GAS in the
#: same run): not a refusal
ANSWERS = ("the region of attraction is the whole state space",)


class Crash(AssertionError):
    """A surface crashed (a traceback, exit 3) or answered outside its contract."""


@dataclass(frozen=True)
class Outcome:
    """One cell: supported (``detail`` is the status or what ran) or refused (``detail`` is the refusal's
    one line); ``via`` names the surface whose refusal this cell carries, when it is not its own."""

    supported: bool
    detail: str
    via: str | None = None


@dataclass(frozen=True)
class Refusal:
    """Cells refused today for one reason: the refusal's words (any of ``says``) and the reason."""

    cells: frozenset[tuple[str, str, str]]
    says: tuple[str, ...]
    reason: str

    def covers(self, kind: str, cls: str, surface: str) -> bool:
        return (kind, cls, surface) in self.cells


def cells(kinds: Sequence[str], classes: Sequence[str], surfaces: Sequence[str]) -> frozenset[tuple[str, str, str]]:
    """Every (kind, class, surface) of the three lists."""
    return frozenset((k, c, s) for k in kinds for c in classes for s in surfaces)


#: every refused cell of today, with its reason (the footnotes of the docs' table, in this order)
REFUSALS: tuple[Refusal, ...] = (
    Refusal(cells(("polynomial", "rational", "functions", "box"), ("sos_bound",), CLASS_SURFACES)
            | cells(("discrete",), ("sos_bound",), CLASS_SURFACES)
            | cells(("map_functions",), ("sos_bound",), CLASS_SURFACES),
            ("has no [disturbances]", "needs [disturbances]"),
            "`sos_bound` bounds how far bounded disturbances push the outputs; a loop without `[disturbances]` "
            "has nothing to bound (its stability classes say where it converges)."),
)


#: loop surfaces refused today, with the refusal's words: (kinds, the words)
LOOP_REFUSALS: tuple[tuple[tuple[str, ...], str], ...] = ()


# -- running the public surfaces ------------------------------------------------------------------------
def cli(*args: str) -> tuple[int, str, str]:
    """``lyapcheck ARGS`` in this process: (exit code, stdout, stderr); a crash raises :class:`Crash`."""
    from click.testing import CliRunner

    from lyapcheck.cli import app

    app._register_commands()
    result = CliRunner().invoke(app.cli, list(args))
    out, err = result.stdout, result.stderr
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise Crash(f"lyapcheck {' '.join(args)}: {type(result.exception).__name__}: {result.exception}")
    if result.exit_code not in (0, 1, 2) or "Traceback" in out + err or "internal error" in err:
        raise Crash(f"lyapcheck {' '.join(args)}: exit {result.exit_code}: {err.strip()[-600:]}")
    return result.exit_code, out, err


def _one_line(text: str, what: str) -> str:
    lines = [line for line in text.strip().splitlines() if line.strip()]
    if len(lines) != 1:
        raise Crash(f"{what}: a refusal must be one line, got {len(lines)}: {text.strip()[:600]}")
    return lines[0]


def _condition(doc: Mapping[str, Any], cls: str, what: str) -> Outcome:
    """A certificate document's answer for ``cls``: supported unless ``not_applicable``."""
    cond = (doc.get("conditions") or {}).get(cls)
    if not isinstance(cond, dict) or cond.get("status") not in STATUSES:
        raise Crash(f"{what}: no documented status for {cls}: {cond!r:.300}")
    if cond["status"] == "not_applicable" and not any(a in str(cond.get("summary")) for a in ANSWERS):
        return Outcome(False, str(cond.get("summary", "")))
    return Outcome(True, cond["status"])


def _inherit(source: Outcome, surface: str) -> Outcome:
    return Outcome(False, source.detail, via=source.via or surface)


@dataclass
class Matrix:
    """The outcomes, ``cells[(kind, class, surface)]`` and ``loop_cells[(kind, surface)]``."""

    cells: dict[tuple[str, str, str], Outcome] = field(default_factory=dict)
    loop_cells: dict[tuple[str, str], Outcome] = field(default_factory=dict)
    #: CPU seconds per kind and surface (what the test costs, for the report)
    seconds: dict[str, float] = field(default_factory=dict)


def model_file(directory: Path, kind: str) -> Path:
    """The kind's model file in ``directory``."""
    path = directory / f"{kind}.toml"
    if not path.exists():
        path.write_text(MODELS[kind])
    return path


def certify_cells(directory: Path, kind: str, *, box: bool) -> dict[str, tuple[Outcome, Path]]:
    """``lyapcheck certify FILE --classes C1,C2,... [--box] --out CERT --json``: one run for every class
    (the certificate then feeds ``verify`` and ``report`` once); where that run is refused in one line,
    each class is run alone, so that each refusal is the class's own."""
    path = model_file(directory, kind)
    with_candidate = kind in CANDIDATE_OVER_BOX
    found = _certify_run(path, list(CLASSES), box=box, with_candidate=with_candidate)
    if any(not found[c][0].supported and found[c][0].via == "run" for c in CLASSES):
        for cls in CLASSES:
            found.update(_certify_run(path, [cls], box=box))
    return found


#: the kinds whose ``certify --box`` takes ``--candidate`` (one V for every value of the box: every kind)
CANDIDATE_OVER_BOX = ("polynomial", "rational", "functions", "disturbances", "box", "discrete", "map_functions")


def _certify_run(path: Path, classes: Sequence[str], *, box: bool, with_candidate: bool = False
                 ) -> dict[str, tuple[Outcome, Path]]:
    out = path.with_name(f"{path.stem}-{'-'.join(classes) if len(classes) == 1 else 'all'}{'-box' if box else ''}.json")
    args = ["certify", str(path), "--classes", ",".join(classes), "--time-limit", str(TIME_LIMIT_S), "--json",
            "--out", str(out)]
    if "candidate" in classes and (len(classes) == 1 or not box or with_candidate):  # a run of several over a
        args += ["--candidate", CANDIDATE]  # box: the class says why it does not apply (but where it is taken)
    if box:
        args += ["--box", BOX]
    code, stdout, stderr = cli(*args)
    if code == 2:  # the whole run refused ("run": split it if it held several classes)
        refused = Outcome(False, _one_line(stderr, " ".join(args)), via="run" if len(classes) > 1 else None)
        return {cls: (refused, out) for cls in classes}
    doc = json.loads(stdout)
    return {cls: (_condition(doc, cls, " ".join(args)), out) for cls in classes}


def verify_file(cert: Path) -> list[dict[str, Any]]:
    """``lyapcheck verify CERT --json``: exit 0 and valid; its checks."""
    code, stdout, stderr = cli("verify", str(cert), "--json")
    checked = json.loads(stdout) if code in (0, 1) else {}
    if code != 0 or not checked.get("valid"):
        raise Crash(f"verify {cert.name}: exit {code}: {stdout[-600:]} {stderr[-300:]}")
    return list(checked["checks"])


def verify_cell(checks: Sequence[Mapping[str, Any]], cls: str, source: Outcome) -> Outcome:
    """The certificate passed ``verify``, and a class that certified has its own check there."""
    if not source.supported:
        return _inherit(source, "certify")
    if source.detail == "certified" and not any(c["check"].startswith(cls) and c["ok"] for c in checks):
        raise Crash(f"verify: no check of {cls}: {[c['check'] for c in checks]}")
    return Outcome(True, "valid")


def report_file(cert: Path) -> str | Outcome:
    """``lyapcheck report CERT --html FILE``: exit 0; the page (or its refusal in one line, exit 2)."""
    html = cert.with_suffix(".html")
    code, stdout, stderr = cli("report", str(cert), "--html", str(html))
    if code == 2:
        return Outcome(False, _one_line(stderr, f"report {cert.name}"))
    if code != 0 or not html.exists():
        raise Crash(f"report {cert.name}: exit {code}: {stderr.strip()[-300:]}")
    return html.read_text(encoding="utf-8")


def report_cell(page: str | Outcome, cls: str, source: Outcome) -> Outcome:
    """The report of the certificate has the class's section (its name on the page)."""
    if not source.supported:
        return _inherit(source, "certify")
    if isinstance(page, Outcome):  # the report refused the certificate
        return page
    if cls not in page:
        raise Crash(f"report: {cls} is not on the page")
    return Outcome(True, "written")


def api_cells(directory: Path, kind: str, cls: str) -> tuple[Outcome, Outcome]:
    """``lyapcheck.certify(model=..., classes=[cls], ...)`` and the ``repr`` of its result."""
    import lyapcheck
    from lyapcheck.errors import LyapcheckError

    kw: dict[str, Any] = {"classes": [cls], "time_limit_s": TIME_LIMIT_S}
    if cls == "candidate":
        kw["candidate"] = CANDIDATE
    if kind == "box":
        kw["box"] = [BOX]
    try:
        result = lyapcheck.certify(model=model_file(directory, kind), **kw)
    except LyapcheckError as exc:
        refused = Outcome(False, _one_line(str(exc), f"lyapcheck.certify({kind}, {cls})"))
        return refused, _inherit(refused, "API result")
    if not isinstance(result, lyapcheck.CertifyResult) or result.conditions[cls].status != \
            result.document["conditions"][cls]["status"]:
        raise Crash(f"lyapcheck.certify({kind}, {cls}): a result whose attributes are not its document's")
    answer = _condition(result.document, cls, f"lyapcheck.certify({kind}, {cls})")
    if not answer.supported:
        return answer, _inherit(answer, "API result")
    text = repr(result)
    if not isinstance(text, str) or cls not in text or answer.detail not in text:
        raise Crash(f"repr of lyapcheck.certify({kind}, {cls}) does not say {cls} {answer.detail}: {text[:300]}")
    return answer, Outcome(True, "says it")


def sweep_cells(directory: Path, kind: str, mode: str) -> dict[str, Outcome]:
    """One sweep of the kind's loop over ``a`` (``points`` or ``boxes``) with every class its spec takes;
    a class the spec refuses (the check ``lyapcheck sweep`` runs first) is refused with its message."""
    from lyapcheck.errors import LyapcheckError
    from sweeps.schema import NOT_COMPUTED, STATUS_CODES
    from sweeps.spec import load_model_spec

    template = POINTS_SPEC if mode == "points" else BOXES_SPEC
    where = directory / f"sweep-{kind}-{mode}"
    where.mkdir(exist_ok=True)
    model = model_file(where, kind)

    def spec(classes: Sequence[str], name: str) -> Path:
        path = where / f"{name}.toml"
        given = f"candidate = {json.dumps(CANDIDATE)}\n" if "candidate" in classes else ""
        path.write_text(template.format(model=model.name, classes=json.dumps(list(classes)), candidate=given))
        return path

    outcomes: dict[str, Outcome] = {}
    for cls in CLASSES:
        try:
            load_model_spec(spec([cls], cls))
        except LyapcheckError as exc:
            outcomes[cls] = Outcome(False, _one_line(str(exc), f"sweep {mode} {kind} {cls}"))
    taken = [c for c in CLASSES if c not in outcomes]
    if not taken:
        return outcomes
    store = where / "out.zarr"
    code, stdout, stderr = cli("sweep", str(spec(taken, "all")), "--out", str(store), "--workers", "0", "--json")
    if code != 0:
        raise Crash(f"sweep {mode} of {kind} ({taken}): exit {code}: {stderr.strip()[-600:]}")
    data = _arrays(store)
    codes = {v: k for k, v in STATUS_CODES.items() if k in STATUSES}
    for cls in taken:
        found = data.get(f"status_{cls}")
        if found is None or len(found) == 0 or any(int(v) == NOT_COMPUTED or int(v) not in codes for v in found):
            raise Crash(f"sweep {mode} of {kind}: status_{cls} is {found!r}")
        outcomes[cls] = Outcome(True, ", ".join(codes[int(v)] for v in found))
    return outcomes


def _arrays(path: Path) -> dict[str, Any]:
    import numpy as np
    import zarr

    group = zarr.open_group(str(path), mode="r")
    return {name: np.asarray(group[name][...]) for name in group.array_keys()}


def simulate_cells(directory: Path, kind: str) -> dict[str, Outcome]:
    """``lyapcheck simulate FILE --json --plot PNG``; ``lyapcheck.simulate(model=...)``'s ``series`` and
    ``repr``. ``box`` simulates one point of its box (``--set``)."""
    import lyapcheck
    from lyapcheck.errors import LyapcheckError

    path = model_file(directory, kind)
    point = ["--set", BOX_POINT] if kind == "box" else []
    png = directory / f"{kind}.png"
    cells: dict[str, Outcome] = {}
    code, stdout, stderr = cli("simulate", str(path), *point, "--json", "--plot", str(png))
    if code == 2:  # the plot refused: the simulation alone
        cells["simulate --plot"] = Outcome(False, _one_line(stderr, f"simulate {kind} --plot"))
        code, stdout, stderr = cli("simulate", str(path), *point, "--json")
    if code == 2:
        cells["simulate"] = Outcome(False, _one_line(stderr, f"simulate {kind}"))
    else:
        doc = json.loads(stdout)
        if not {"trajectories", "diverged", "sup_abs_output_tail"} <= set(doc):
            raise Crash(f"simulate {kind} --json: keys {sorted(doc)}")
        cells["simulate"] = Outcome(True, f"{doc['n_trajectories']} trajectories")
        if "simulate --plot" not in cells:
            if not png.read_bytes().startswith(b"\x89PNG"):
                raise Crash(f"simulate {kind} --plot: {png} is not a PNG")
            cells["simulate --plot"] = Outcome(True, "written")
    try:
        report = lyapcheck.simulate(model=path, settings=[BOX_POINT] if kind == "box" else None)
    except LyapcheckError as exc:
        refused = Outcome(False, _one_line(str(exc), f"lyapcheck.simulate({kind})"))
        return {**cells, "series": refused, "repr": _inherit(refused, "series")}
    series = report.series
    if series is None:
        cells["series"] = Outcome(False, "series is None")
    else:
        axis = "step" if "step" in series.dims else "time"  # a map's iterates are over steps
        if "x" not in series or series["x"].sizes.get(axis, 0) < 2:
            raise Crash(f"lyapcheck.simulate({kind}).series: {series!r:.300}")
        cells["series"] = Outcome(True, f"{series['x'].sizes[axis]} {axis}s")
    text = repr(report)
    if not isinstance(text, str) or not text.strip():
        raise Crash(f"repr of lyapcheck.simulate({kind}) is empty")
    cells["repr"] = Outcome(True, "says it")
    return cells


# -- building the whole matrix ----------------------------------------------------------------------------
def build(directory: Path, kinds: Sequence[str] = KINDS, progress: Callable[[str], None] | None = None) -> Matrix:
    """Exercise every cell of ``kinds`` in ``directory``. Work is shared: one ``certify`` run per kind (and
    one over the box) for all its classes feeds one ``verify`` and one ``report``; one sweep per kind and
    mode; the box kind's sweeps are the polynomial loop's. The API is called once per class, so that each
    class also runs alone (``roa`` without a GAS proof beside it)."""
    import time

    matrix = Matrix()
    swept: dict[tuple[str, str], dict[str, Outcome]] = {}

    def timed(what: str, work: Callable[[], Any]) -> Any:
        start = time.process_time()
        value = work()
        matrix.seconds[what] = matrix.seconds.get(what, 0.0) + time.process_time() - start
        return value

    for kind in kinds:
        if progress:
            progress(kind)
        sweep_kind = "polynomial" if kind == "box" else kind  # the same loop over the same interval
        for mode in ("points", "boxes"):
            if (sweep_kind, mode) not in swept:
                swept[sweep_kind, mode] = timed(f"{kind} sweep {mode}",
                                                lambda: sweep_cells(directory, sweep_kind, mode))
        certified = timed(f"{kind} certify", lambda: certify_cells(directory, kind, box=kind == "box"))
        over_box = certified if kind == "box" else timed(f"{kind} --box",
                                                         lambda: certify_cells(directory, kind, box=True))
        verified: dict[Path, list[dict[str, Any]]] = {}
        pages: dict[Path, str | Outcome] = {}
        for cls in CLASSES:
            cert, path = certified[cls]
            if cert.supported and path not in verified:  # each certificate file once, for all its classes
                verified[path] = timed(f"{kind} verify", lambda: verify_file(path))
                pages[path] = timed(f"{kind} report", lambda: report_file(path))
            api, shown = timed(f"{kind} API", lambda: api_cells(directory, kind, cls))
            row = {"certify": cert, "verify": verify_cell(verified.get(path, []), cls, cert), "--box": over_box[cls][0],
                   "sweep points": swept[sweep_kind, "points"][cls], "sweep boxes": swept[sweep_kind, "boxes"][cls],
                   "report": report_cell(pages.get(path, ""), cls, cert), "API result": api, "repr": shown}
            for surface, outcome in row.items():
                matrix.cells[kind, cls, surface] = outcome
        for surface, outcome in timed(f"{kind} simulate", lambda: simulate_cells(directory, kind)).items():
            matrix.loop_cells[kind, surface] = outcome
    return matrix


def problems(matrix: Matrix) -> list[str]:
    """Every refused cell without a documented reason whose words it says, and every documented refusal
    whose cell is supported (the table cannot go stale)."""
    found = []
    for (kind, cls, surface), outcome in sorted(matrix.cells.items()):
        entries = [r for r in REFUSALS if r.covers(kind, cls, surface)]
        if outcome.supported and entries:
            found.append(f"{kind} / {cls} / {surface}: documented as refused, but supported ({outcome.detail})")
        elif not outcome.supported and not entries:
            found.append(f"{kind} / {cls} / {surface}: refused without a documented reason: {outcome.detail}")
        elif not outcome.supported and not any(s in outcome.detail for r in entries for s in r.says):
            found.append(f"{kind} / {cls} / {surface}: refused, but not for the documented reason: {outcome.detail}")
    for (kind, surface), outcome in sorted(matrix.loop_cells.items()):
        if not outcome.supported and not any(kind in kinds and says in outcome.detail for kinds, says in LOOP_REFUSALS):
            found.append(f"{kind} / {surface}: refused without a documented reason: {outcome.detail}")
    return found


# -- the docs' table -------------------------------------------------------------------------------------
BEGIN = "<!-- feature-matrix: generated by `python -m tests.feature_matrix --write`; do not edit -->"
END = "<!-- feature-matrix: end -->"
DOC = Path(__file__).resolve().parents[1] / "docs" / "model-files.md"
_LETTERS = "abcdefghijklmnopqrstuvwxyz"


def footnote(kind: str, cls: str, surface: str) -> str:
    """The letter of the first refusal entry covering the cell; ``?`` for none (a problem the test reports)."""
    for i, entry in enumerate(REFUSALS):
        if entry.covers(kind, cls, surface):
            return _LETTERS[i]
    return "?"


def table(matrix: Matrix) -> str:
    """The markdown between the markers: one table per loop kind, then the loop-level surfaces."""
    lines: list[str] = []
    for kind in KINDS:
        if not any(k == kind for k, _, _ in matrix.cells):
            continue
        lines += [KIND_TITLES[kind], "", "| class | " + " | ".join(f"`{s}`" if s.startswith("--") else s
                                                                               for s in CLASS_SURFACES) + " |",
                  "|---" * (len(CLASS_SURFACES) + 1) + "|"]
        for cls in CLASSES:
            marks = ["yes" if matrix.cells[kind, cls, s].supported else f"({footnote(kind, cls, s)})"
                     for s in CLASS_SURFACES]
            lines.append(f"| `{cls}` | " + " | ".join(marks) + " |")
        lines.append("")
    lines += ["**Surfaces of the loop** (`repr` here is that of `lyapcheck.simulate(...)`'s result)", "",
              "| loop | " + " | ".join(f"`{s}`" if s != "series" else "`series`" for s in LOOP_SURFACES) + " |",
              "|---" * (len(LOOP_SURFACES) + 1) + "|"]
    for kind in KINDS:
        if any(k == kind for k, _ in matrix.loop_cells):
            lines.append(f"| {kind} | " + " | ".join("yes" if matrix.loop_cells[kind, s].supported else "no"
                                                     for s in LOOP_SURFACES) + " |")
    lines += ["", "Refused, and why:", ""]
    used = {footnote(*key) for key, o in matrix.cells.items() if not o.supported}
    for i, entry in enumerate(REFUSALS):
        if _LETTERS[i] in used:
            lines.append(f"- ({_LETTERS[i]}) {entry.reason}")
    for kinds, says in LOOP_REFUSALS:  # (a loop surface's "no")
        if any(k in kinds and not o.supported for (k, _), o in matrix.loop_cells.items()):
            lines.append(f"- {', '.join(kinds)}, surfaces of the loop: {says} (simulate refuses it in one line).")
    return "\n".join(lines) + "\n"


KIND_TITLES = {
    "polynomial": "**Polynomial loop** (`x2' = -x1 - a*x2 - x2**3`)",
    "rational": "**Rational loop** (`x2' = -x1 - a*x2 - x2/(1 + x1**2)`)",
    "functions": "**Loop with functions** (`sin`, `sat`)",
    "disturbances": "**Loop with disturbances** (`x1' = -a*x1 + x2 + d`, `|d| <= 0.1`)",
    "box": "**Over a box** (`--box a=0.8..1.2` on certify, verify, report and the API; the sweeps are the "
           "polynomial loop's over that interval)",
    "discrete": "**Discrete-time map** (`[model] time = \"discrete\"`: `x2+ = -x1/4 + a*x2/2 - x2**3/8`)",
    "map_functions": "**Discrete-time map with functions** (`x1+ = x1/2 + sin(x2)/4`, `x2+ = -x1/4 + "
                     "a*tanh(x2)/2`)",
}


def replaced(doc: str, generated: str) -> str:
    """``doc`` with the text between the markers replaced by ``generated``."""
    pattern = re.compile(re.escape(BEGIN) + r"\n.*?" + re.escape(END), re.S)
    if len(pattern.findall(doc)) != 1:
        raise ValueError(f"{DOC}: expected the markers {BEGIN!r} ... {END!r} once")
    return pattern.sub(lambda _: f"{BEGIN}\n{generated}{END}", doc)


def documented() -> str:
    """The text between the markers in docs/model-files.md."""
    doc = DOC.read_text(encoding="utf-8")
    start, end = doc.index(BEGIN) + len(BEGIN) + 1, doc.index(END)
    return doc[start:end]


def _main(argv: Sequence[str]) -> int:
    import os
    import tempfile

    os.environ["LYAPCHECK_CERTIFICATE_STORE"] = "off"  # every cell searches, as the test does
    with tempfile.TemporaryDirectory(prefix="feature-matrix-") as tmp:
        matrix = build(Path(tmp), progress=lambda kind: print(f"  {kind} ...", file=sys.stderr))
    for line in problems(matrix):
        print(line, file=sys.stderr)
    generated = table(matrix)
    if "--write" in argv:
        DOC.write_text(replaced(DOC.read_text(encoding="utf-8"), generated), encoding="utf-8")
        print(f"wrote the table into {DOC}")
        return 0
    if "--check" in argv:
        return 0 if documented() == generated else 1
    print(generated)
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))
