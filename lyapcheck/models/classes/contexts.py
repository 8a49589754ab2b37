"""What each class's entry in :mod:`lyapcheck.models.classes.registry` is given: one context object per kind
of loop, built once by the surface that runs or verifies it.

==========================  =========================================================================
context                     for
==========================  =========================================================================
:class:`FieldRun`           a class's search on a polynomial or rational loop: the field in deviations,
                            multiplied through and scaled, its nominal and robust forms, the box
:class:`FunctionsRun`       a class's search on a loop with functions: the proved recasting (and the
                            one with a box's parameters as bounded constants), the box
:class:`FieldCheck`         verify on a polynomial or rational loop: the field re-derived from the model
                            text (shifted; cleared and scaled once its denominators' proofs passed)
:class:`FunctionsCheck`     verify on a loop with functions: the recasting re-derived from the model
                            text (or recast again with a box's parameters as bounded constants), the
                            disturbances (or the box's parameters) as balls, the model text
:class:`MapRun`             a class's search on a polynomial discrete-time map: the map shifted to its
                            fixed point, the user's V
:class:`MapCheck`           verify on a polynomial discrete-time map: the shifted map re-derived from the
                            model text
:class:`MapFunctionsRun`    a class's search on a discrete-time map with functions: its model (the
                            recasting of its displacement ``F(x) - x``)
:class:`MapFunctionsCheck`  verify on such a map: its model, read again from the model text
:class:`SampledRun`         a class's search on a sampled-data loop: its model (plant, controller,
                            period)
:class:`SampledCheck`       verify on a sampled-data loop: its model, read again from the model text
==========================  =========================================================================

A check context of a kind of loop where some classes have no check (a map, a sampled-data loop) says
in :meth:`MapCheck.not_checked` (and its siblings') words why a decided claim of such a class fails
(:func:`lyapcheck.models.classes.registry.verify`).

Every entry's run callable takes a run context and the class's :class:`~lyapcheck.models.engines.search.Budget`
and returns its :class:`~lyapcheck.results.ConditionResult`; every verify callable takes the class's
name, a decided condition as stored (``c``: status, figures, certificate) and a check context, and
returns ``(ok, why)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel
    from lyapcheck.models.language.sampling import SampledModel
    from lyapcheck.models.loop.field import ScaledField, ShiftedField, StateField
    from lyapcheck.models.classes.recast_classes import Loop
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.results import ConditionResult, Disturbances
    from lyapcheck.sos.polynomials import Poly


@dataclass
class Candidate:
    """The user's ``V``: the text as given, and the polynomial in the declared (unshifted) states."""

    text: str
    poly: "Poly"


@dataclass
class FieldRun:
    """A polynomial or rational loop as its classes are run on it."""

    model: "Model"
    #: the field in deviations (over a box: with the box's parameters as coordinates)
    shifted: "ShiftedField"
    box: "ModelBox | None"
    #: the user's V (``--candidate``), if given
    candidate: "Candidate | None"
    #: the decided classes so far, in the order they ran (a class may read an earlier one's result)
    results: "dict[str, ConditionResult]"
    #: the field multiplied through and scaled (None where a denominator was not proved of one sign:
    #: the classes that need it are then not run)
    scaled: "ScaledField | None" = None
    #: the field with every disturbance that enters a box coordinate, where a robust claim can exist
    robust: "StateField | None" = None
    #: the field with the disturbances at 0
    nominal: "StateField | None" = None
    #: some disturbance enters the field
    enters: bool = False
    #: what a claim on the nominal field covers (None without disturbances)
    nominal_covers: "Disturbances | None" = None

    @property
    def cleared(self) -> "ScaledField":
        """The cleared, scaled field (a class that needs it runs only where it exists)."""
        if self.scaled is None:
            raise ValueError("the field was not multiplied through")
        return self.scaled


@dataclass
class FunctionsRun:
    """A loop with functions as its classes are run on it."""

    model: "RecastModel"
    #: the recasting in deviations, its square roots' bounds proved (over a box: at its centre)
    loop: "Loop"
    #: the loop the relations' classes prove on: ``loop``, or over a box the loop recast with the box's
    #: parameters as bounded constants, its square roots' bounds proved
    proved: "Loop"
    box: "ModelBox | None"
    #: the user's V (``--candidate``), shifted, if given
    candidate: "Poly | None"
    #: the decided classes so far
    results: "dict[str, ConditionResult]"
    _linearization: "ConditionResult | None" = None

    def linearization(self, budget: "Budget | None" = None) -> "ConditionResult":
        """The recasting's linearization at the equilibrium (computed once: ``linearization`` and
        ``roa`` read it; ``budget`` the first caller's class's, for the piecewise-linear route's search)."""
        if self._linearization is None:  # (the Jacobian's, or at a kink the piecewise-linear route's)
            from lyapcheck.models.classes.piecewise_linearization import linearization

            self._linearization = linearization(self.loop, budget)
        return self._linearization


@dataclass(frozen=True)
class FieldCheck:
    """A polynomial or rational loop's field as verify re-derives it."""

    #: the field in deviations (over a box: with the box's parameters as coordinates)
    shifted: "ShiftedField"
    #: the field multiplied through and scaled (None before its denominators' proofs are checked:
    #: only ``linearization``, which reads the field as it is, is verified then)
    scaled: "ScaledField | None" = None


@dataclass(frozen=True)
class FunctionsCheck:
    """A loop with functions as verify re-derives it."""

    #: the recasting in deviations (or the loop recast with a box's parameters as bounded constants)
    base: "Loop"
    #: the disturbances, or a box's parameters, as balls for a ball-arithmetic region (None: at 0)
    robust: Any = None
    #: the model text's model (None over a box's bounded constants: a safety class then refuses)
    model: "RecastModel | None" = None
    #: the box of parameters the document claims, if any
    box: "ModelBox | None" = None


@dataclass
class MapRun:
    """A polynomial discrete-time map as its classes are run on it (its disturbances at 0:
    :mod:`lyapcheck.models.loop.discrete`; but ``sos_bound``, which reads them from the shifted map's ring:
    :mod:`lyapcheck.models.classes.discrete_bounds`)."""

    model: "Model"
    #: the map shifted to its fixed point, ``e+ = f(x_eq + e) - x_eq``
    #: (:func:`lyapcheck.models.loop.discrete.shifted_map`)
    shifted: "ShiftedField"
    #: the user's V (``--candidate``), if given
    candidate: "Candidate | None"
    #: the decided classes so far
    results: "dict[str, ConditionResult]"


@dataclass(frozen=True)
class MapCheck:
    """A polynomial discrete-time map as verify re-derives it."""

    #: the map shifted to its fixed point, re-derived from the model text
    shifted: "ShiftedField"
    model: "Model"

    @staticmethod
    def not_checked(status: object) -> str:
        """Why a decided claim of a class without a check on a map fails."""
        return f"a {status} claim on a discrete-time map that no discrete-time check re-derives"


@dataclass
class MapFunctionsRun:
    """A discrete-time map with functions as its classes are run on it."""

    #: the map, its displacement ``F(x) - x`` recast (:mod:`lyapcheck.models.classes.discrete_functions`;
    #: over a box, read at the box's centre)
    model: "RecastModel"
    #: the box of parameters its classes hold over (``--box``), if any
    #: (:mod:`lyapcheck.models.classes.discrete_functions_box`)
    box: "ModelBox | None" = None


@dataclass(frozen=True)
class MapFunctionsCheck:
    """A discrete-time map with functions as verify re-reads it from the model text."""

    model: "RecastModel"
    #: the document's box (its fixed point checked to stay put over it), if any
    box: "ModelBox | None" = None

    @staticmethod
    def not_checked(status: object) -> str:
        """Why a decided claim of a class without a check on such a map fails."""
        return f"a {status} claim on a discrete-time map with functions that no check re-derives"


@dataclass
class SampledRun:
    """A sampled-data loop as its classes are run on it."""

    #: the plant, the controller's laws and the period (:mod:`lyapcheck.models.language.sampling`)
    model: "SampledModel"


@dataclass(frozen=True)
class SampledCheck:
    """A sampled-data loop as verify re-reads it from the model text."""

    model: "SampledModel"

    @staticmethod
    def not_checked(status: object) -> str:
        """Why a decided claim of a class without a check on a sampled-data loop fails."""
        return f"a {status} claim on a sampled-data loop that no check re-derives"


__all__ = ["Candidate", "FieldRun", "FunctionsRun", "FieldCheck", "FunctionsCheck", "MapRun", "MapCheck",
           "MapFunctionsRun", "MapFunctionsCheck", "SampledRun", "SampledCheck"]
