"""What each class's entry in :mod:`lyapcheck.models.classes.registry` is given: one context object per kind
of loop, built once by the surface that runs or verifies it.

======================  =========================================================================
context                 for
======================  =========================================================================
:class:`FieldCheck`     verify on a polynomial or rational loop: the field re-derived from the model
                        text (shifted; cleared and scaled once its denominators' proofs passed)
:class:`FunctionsCheck` verify on a loop with functions: the recasting re-derived from the model
                        text (or recast again with a box's parameters as bounded constants), the
                        disturbances (or the box's parameters) as balls, the model text
======================  =========================================================================

Every entry's verify callable takes a decided condition as stored (``c``: status, figures,
certificate) and one of these, and returns ``(ok, why)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel
    from lyapcheck.models.loop.field import ScaledField, ShiftedField
    from lyapcheck.models.classes.recast_classes import Loop


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


__all__ = ["FieldCheck", "FunctionsCheck"]
