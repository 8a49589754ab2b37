"""Discrete-time maps (``[model] time = "discrete"``): the shifted map and the one guard.

In a map's model file ``[dynamics]`` gives each state's next value, ``x+ = f(x)``; its equilibrium is
a fixed point, ``f(x_eq) = x_eq`` (checked exactly when the file is read:
:func:`lyapcheck.models.language.modelfile.check_equilibrium`), and the map shifted to it is
``e+ = f(x_eq + e) - x_eq`` (:func:`shifted_map`), which keeps 0 fixed.

Soundness first: a map must never reach code that reads ``[dynamics]`` as an ODE (a stable map read as a
field is another system, often refuted). Two places guard it:

- classes: a class with a discrete-time condition has a ``run_map`` and a ``verify_map`` entry in
  :mod:`lyapcheck.models.classes.registry` (a map with functions: ``run_map_functions`` and
  ``verify_map_functions``), given the shifted map (:class:`~lyapcheck.models.classes.contexts.MapRun`,
  :class:`~lyapcheck.models.classes.contexts.MapCheck`); :data:`lyapcheck.models.classes.registry.DISCRETE`
  lists them. The one runner (``lyapcheck.models.surfaces.certify``, where classes are chosen) makes every
  other class ``not_applicable`` on a map with :func:`not_decided`, and ``verify`` fails a decided claim
  of one (:func:`lyapcheck.models.classes.registry.verify`);
- surfaces that would integrate or bound the map as a field (box sweeps) call :func:`refuse`
  first: one line, exit 2, naming ``time = "discrete"``. Reports and point sweeps iterate a map instead
  (:mod:`reports.map_figures`, :class:`sweeps.crosscheck._MapLoop`, through
  :func:`lyapcheck.models.surfaces.iterate.iterate`). ``certify --box`` takes a polynomial map: ``quadratic``
  and ``sos_gas`` prove a V for every parameter value of the box
  (:mod:`lyapcheck.models.classes.discrete_lyapunov`), the other classes are ``not_applicable`` over a box.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Final

from lyapcheck.errors import ModelFileError
from lyapcheck.sos.polynomials import to_fmpq

if TYPE_CHECKING:  # pragma: no cover
    from fractions import Fraction
    from typing import Mapping, Sequence

    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.loop.field import ShiftedField

#: the words every refusal and every not_applicable sentence names
TIME_WORDS: Final = '[model] time = "discrete"'


def is_discrete(model: object) -> bool:
    """Whether ``model`` (any kind of loop, or anything with a ``time``) is a discrete-time map."""
    return getattr(model, "time", "continuous") == "discrete"


def not_decided(name: str, taken: "Sequence[str]") -> str:
    """The ``not_applicable`` sentence of a class without a discrete-time condition (no ``run_map`` entry), on a
    map; ``taken``: the classes that have one (:data:`lyapcheck.models.classes.registry.DISCRETE`)."""
    return (f"{name} is not yet decided for discrete-time maps ({TIME_WORDS}: [dynamics] gives each state's next "
            f"value, not its time derivative); the classes taken on a map: {', '.join(taken)}")


def refuse(model: object, surface: str, what: str = "") -> None:
    """Raise the one-line refusal (exit 2) of ``surface`` (``--box``, ``sweep``, ...) when ``model`` is a
    map; ``what`` says what to do instead."""
    if is_discrete(model):
        source = str(getattr(model, "source", "<model>"))
        raise ModelFileError(source, surface, f"not taken yet for a discrete-time map ({TIME_WORDS})"
                                              + (f"; {what}" if what else ""))


def shifted_map(model: "Model", parameters: "Mapping[str, Fraction] | None" = None,
                box: "ModelBox | None" = None) -> "ShiftedField":
    """``e+ = f(x_eq + e) - x_eq`` as a :class:`~lyapcheck.models.loop.field.ShiftedField` (numerators over
    denominators, exact): :func:`~lyapcheck.models.loop.field.shifted_field` moves the argument, and each
    numerator ``N_i`` becomes ``N_i - x_eq,i D_i`` so that 0 is the map's fixed point (``N_i(0) = 0``, which
    the Jacobian's quotient rule in :func:`lyapcheck.models.classes.linearization.jacobian` relies on). With a
    ``box``, its parameters stay variables of the ring, normalized to ``[-1, 1]``, as in
    :func:`~lyapcheck.models.loop.field.shifted_field`."""
    from dataclasses import replace

    from lyapcheck.models.loop.field import shifted_field

    if not is_discrete(model):
        raise ValueError("shifted_map takes a discrete-time map")
    shifted = shifted_field(model, parameters, box=box)
    numerators = tuple(num - den * to_fmpq(x) if x else num
                       for num, den, x in zip(shifted.numerators, shifted.denominators, model.equilibrium))
    return replace(shifted, numerators=numerators)


__all__ = ["TIME_WORDS", "is_discrete", "not_decided", "refuse", "shifted_map"]
