"""The interface of a report section: what one family of condition classes shows on a certificate page.

A *section* renders the classes of one family (its ``titles`` name them) for one kind of model
(``model``: :data:`PAPER` for the paper's ILOS loop, :data:`MODEL_FILE` for any model file).
For each condition of a document the page asks the registry (:mod:`reports.sections`) for the
section of the document's model and the class's name, and the section returns a
:class:`ClassView`, the one shape the page template shows: title, status, summary, key figures,
typeset polynomials and matrices, exact numbers, notes, comparisons and every stored figure.

A section may also put certified sets on a model's phase portrait (:meth:`Section.portrait`):
sets ``{V <= level}`` drawn filled (:class:`LevelSet`: regions of attraction, attracting sets,
invariant sets of safety certificates) and global Lyapunov functions the simulated trajectories
are checked against (:class:`GlobalV`).

Everything here reads document data defensively: a malformed value is shown as text or left
out, never raised.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Final

from reports.polynomials import ExactPolynomial
from reports.typeset import Equation, Equations
from reports.views import Item

#: the model a section's classes belong to: the paper's ILOS/ODS loop (``lyapcheck certify
#: paper.toml``), or any model file (``lyapcheck certify --model FILE``)
PAPER: Final = "paper"
MODEL_FILE: Final = "model-file"
#: a loop with functions (a model certificate with a ``"recast"`` table): its classes are shown by the
#: model file's section (:class:`reports.sections.model_file.ModelFileSection`) made for this model
RECAST_LOOP: Final = "recast-loop"
#: the colour of each class's certified region on the phase portrait (a polynomial loop's and a
#: loop with functions')
SET_COLOURS: Final = {"roa": "#1a7f37", "candidate": "#0969da"}


def text_of(value: object) -> str:
    """A document value as page text: strings as they are, ``None`` as a dash, the rest by ``str``."""
    return value if isinstance(value, str) else ("—" if value is None else str(value))


@dataclass
class PolynomialView:
    """An exact polynomial: typeset (maybe truncated), as plain text, and what was left out."""

    title: str
    eq: Equation | None
    plain: str
    notes: list[str]
    terms: int
    degree: int


@dataclass
class ClassView:
    """One condition class as the page shows it (the template prints every non-empty part, in this order).

    ``figures`` are the key figures of the table at the top (one short phrase each); ``items``
    every stored figure not shown otherwise (under ``items_title`` when it is set).
    """

    name: str
    anchor: str
    title: str
    status: str
    summary: str
    property: str = ""
    property_meaning: str = ""
    figures: list[str] = field(default_factory=list)
    polynomials: list[PolynomialView] = field(default_factory=list)
    exact: list[tuple[str, str, str]] = field(default_factory=list)
    matrices: list[Item] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    grams: list[str] = field(default_factory=list)
    #: a certified value beside a formula of the source: (what, equation, note)
    comparison: list[tuple[str, Equation | None, str]] = field(default_factory=list)
    #: certified against the worst simulated disturbance: (what, value) rows, or why there are none
    tightness: list[tuple[str, str]] = field(default_factory=list)
    tightness_note: str = ""
    #: matrices derived from the certificate on the spot (shown under "Derived from the certificate")
    extra: list[Item] = field(default_factory=list)
    #: tables of the class (the sets it is about, its falsification), shown after the notes
    tables: list[TableView] = field(default_factory=list)
    items: list[Item] = field(default_factory=list)
    items_title: str = ""


@dataclass
class TableView:
    """A small table of a class: a title, column heads, rows of text cells, and a note under it."""

    title: str
    heads: tuple[str, ...]
    rows: list[tuple[str, ...]]
    note: str = ""


@dataclass(frozen=True)
class ClassContext:
    """What a section may read beside its own condition: the document and the model's names.

    ``states`` and ``shifts`` (the equilibrium, exact) name and place the polynomials of a model
    file's certificates; ``outputs`` are its outputs; ``box`` the document's box of parameters,
    if any; ``set_text`` the model's ``[sets]`` as written (key -> each piece's strings), read
    from the stored model text. ``eqs`` collects the page's equations (typeset together, once).
    """

    doc: dict[str, Any]
    eqs: Equations
    states: list[str] = field(default_factory=list)
    shifts: list[Fraction] = field(default_factory=list)
    outputs: tuple[str, ...] = ()
    box: Any = None
    set_text: dict[str, tuple[tuple[str, ...], ...]] = field(default_factory=dict)


@dataclass(frozen=True)
class LevelSet:
    """A certified set ``{V <= level}`` of the document, drawn on the phase portrait.

    ``kind`` is ``"region"`` (roa, candidate: invariant, every start converges),
    ``"attracting"`` (sos_bound: every trajectory enters it, for every admissible disturbance;
    ``rate`` is its certified decay rate ``lam`` per second, ``output`` and ``bound`` the output
    it bounds and the certified ``limsup |y|``) or ``"invariant"`` (barrier ``{B <= 0}``,
    reach_avoid ``{V <= 0}``: no trajectory that starts in it leaves it, and none from the model's
    initial set enters its unsafe set; no convergence is claimed). ``until`` names a set of the
    model (``"goal"``) on reaching which the claim ends (reach_avoid claims nothing after the
    goal); ``symbol`` is the function's letter in the page's words (``B``, ``V``).
    """

    name: str
    label: str
    poly: ExactPolynomial
    level: Fraction
    kind: str
    colour: str
    rate: float = 0.0
    output: str = ""
    bound: float | None = None
    until: str = ""
    symbol: str = "V"


@dataclass(frozen=True)
class GlobalV:
    """A global Lyapunov function (``quadratic``, ``sos_gas``), with its certified decay rate of V."""

    name: str
    poly: ExactPolynomial
    rate: float


@dataclass(frozen=True)
class PortraitPart:
    """What one certified class puts on the phase portrait of a 2-state model."""

    sets: tuple[LevelSet, ...] = ()
    globals: tuple[GlobalV, ...] = ()


class Section:
    """One family of condition classes on the certificate page (subclass it; see :mod:`reports.sections`).

    Attributes
    ----------
    model
        :data:`PAPER`, :data:`MODEL_FILE` or :data:`RECAST_LOOP`: the model whose documents carry these classes.
    titles
        Class name -> what a reader should call it; the keys are the classes this section renders.
    """

    model: str = MODEL_FILE
    titles: dict[str, str] = {}

    def view(self, name: str, cond: Any, index: int, ctx: ClassContext) -> ClassView:
        """The page's view of the condition ``name`` as stored (``cond``: normally a mapping, but a
        malformed file may hold anything; ``index``: its place on the page, from 1)."""
        raise NotImplementedError

    def portrait(self, name: str, cond: dict[str, Any], n: int, time_scale: Fraction) -> PortraitPart:
        """The sets and functions of a *certified* condition for the phase portrait (``n`` states;
        ``time_scale`` ``T`` of the certificate's scaled time ``t = T tau``). Raises ValueError
        for a polynomial that cannot be read (the portrait says so)."""
        return PortraitPart()


__all__ = ["PAPER", "MODEL_FILE", "RECAST_LOOP", "SET_COLOURS", "ClassView", "ClassContext", "PolynomialView",
           "LevelSet", "GlobalV", "PortraitPart", "Section", "TableView", "text_of"]
