"""Boxes of a model's parameters: ``--box "mu=0.8..1.2"``, one certificate for every value in it.

In the certificates a box parameter ``theta_i in [lo_i, hi_i]`` is written ``c_i + h_i u_i`` with
``c_i`` the centre, ``h_i`` the half-width and ``u_i in [-1, 1]`` (exact rationals); the box
enters every identity through multipliers ``s_i (1 - u_i^2)`` with ``s_i`` a sum of squares
(the S-procedure: ``1 - u_i^2 >= 0`` exactly on the box), so each identity holds for every
parameter value of the box. A certificate's polynomials may depend on ``u`` (a parameter-dependent
``V``, the standard robust-SOS construction; a common ``V`` is its degree-0 case). A box widened
after the fact changes ``c`` and ``h``, so the identities no longer hold and ``verify`` fails.

A box is checked when it is given: its names are the model's parameters, each range non-empty
(``lo < hi``), the equilibrium is one for every value in the box (exactly: the right-hand sides at
the equilibrium vanish identically in the box's parameters; a discrete-time map's fixed point stays
put, ``f(x_eq) = x_eq`` identically), and the model is defined on the whole
box (every denominator at the equilibrium is proved non-zero on it). Bad boxes are one-line exit-2
errors naming the field.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Mapping, Sequence

from lyapcheck.errors import InvalidParameter, ModelFileError
from lyapcheck.models.language.modelfile import Model
from lyapcheck.models.language.parameter_box import ModelBox

__all__ = ["ModelBox", "parse_model_box", "parse_box_of", "check_box"]


def parse_model_box(model: Model, specs: Sequence[str] | Mapping[str, Any]) -> ModelBox:
    """``["mu=0.8..1.2", "d=0.05 mm/s..0.1 mm/s"]`` (or ``{"mu": (0.8, 1.2)}``) for ``model``,
    validated (see the module docstring)."""
    box = parse_box_of(model.source, model.parameters, specs)
    check_box(model, box)
    return box


def parse_box_of(source: str, parameters: Mapping[str, Any], specs: Sequence[str] | Mapping[str, Any]) -> ModelBox:
    """The box's names and ranges, read and checked against the model's ``parameters`` (not yet its
    loop: :func:`check_box`, or a loop with functions' own check)."""
    from lyapcheck.units import parse_si_quantity

    items: list[tuple[str, Any, Any, str]] = []
    if isinstance(specs, Mapping):
        for name, value in specs.items():
            if not isinstance(value, (list, tuple)) or len(value) != 2:
                raise InvalidParameter("box", "NAME: (lo, hi)", f"{name}: {value!r}")
            items.append((str(name), value[0], value[1], f"{name}={value[0]}..{value[1]}"))
    else:
        for spec in specs:
            name, sep, interval = str(spec).partition("=")
            if not sep or ".." not in interval:
                raise InvalidParameter("box", "NAME=LO..HI, e.g. 'mu=0.8..1.2'", spec)
            lo_text, _, hi_text = interval.partition("..")
            items.append((name.strip(), lo_text.strip(), hi_text.strip(), str(spec)))
    if not items:
        raise InvalidParameter("box", "at least one NAME=LO..HI", "")
    given: dict[str, tuple[Fraction, Fraction]] = {}
    for name, lo_text, hi_text, spec in items:
        if name not in parameters:
            known = ", ".join(parameters) or "none"
            raise ModelFileError(source, f"--box {name}", f"no parameter named '{name}' (parameters: {known})")
        if name in given:
            raise ModelFileError(source, f"--box {name}", "given twice")
        try:
            lo, hi = parse_si_quantity(name, lo_text), parse_si_quantity(name, hi_text)
        except InvalidParameter as exc:
            raise ModelFileError(source, f"--box {name}", f"must be LO..HI with numbers or unit strings, "
                                                          f"got {exc.got!r}") from None
        if not lo < hi:
            raise ModelFileError(source, f"--box {name}", f"an empty range: lo must be below hi, got '{spec}'")
        given[name] = (lo, hi)
    return ModelBox(tuple((name, *given[name]) for name in parameters if name in given))


def check_box(model: Model, box: ModelBox) -> None:
    """The equilibrium is one for every parameter of the box, and the model is defined there."""
    from lyapcheck.models.loop.discrete import is_discrete, shifted_map
    from lyapcheck.models.loop.field import shifted_field
    from lyapcheck.sos.polynomials import Ring

    where = f"--box {', '.join(box.names)}"
    try:
        # a map's fixed point must stay put: its shifted map e+ = f(x_eq + e) - x_eq vanishes at e = 0 for every
        # value of the box (a field's equilibrium: its right-hand sides vanish there)
        shifted = shifted_map(model, box=box) if is_discrete(model) else shifted_field(model, box=box)
    except ValueError as exc:  # an output divided by a box parameter: not supported over a box
        raise ModelFileError(model.source, where, str(exc)) from None
    ring = shifted.ring
    n = model.n
    origin = {name: Fraction(0) for name in ring.names[:n]} | {d: Fraction(0) for d in model.disturbances}
    u_ring = Ring(box.names)
    for s, num, den in zip(model.states, shifted.numerators, shifted.denominators):
        if not ring.substitute(num, origin).is_zero():
            if is_discrete(model):
                raise ModelFileError(model.source, where, f"the map's fixed point moves with the box's parameters: "
                                                          f"{s}+ is not {s} there for some value of the box (checked "
                                                          "exactly); certify a point with --set NAME=VALUE")
            raise ModelFileError(model.source, where, f"the equilibrium moves with the box's parameters: {s}' is not 0 "
                                                      "there for every value of the box (checked exactly)")
        den_eq = ring.restrict(ring.substitute(den, origin), u_ring)
        if not _nonzero_on_box(u_ring, den_eq):
            raise ModelFileError(model.source, where, f"the model is not defined on the whole box: the denominator of "
                                                      f"{s} at the equilibrium, {str(den_eq).replace('^', '**')} in the "
                                                      "normalized parameters u in [-1, 1], could not be proved non-zero "
                                                      "there")


def _nonzero_on_box(ring: Any, p: Any) -> bool:
    """Exactly: ``p(u) != 0`` for every ``u`` in ``[-1, 1]^k``. A constant is decided at once; one
    variable by isolating the real roots (Arb, rigorous); more by a sign proof (an SOS certificate
    of ``+-p - c`` on the box), else refused."""
    if p.is_constant():
        return not p.is_zero()
    k = ring.nvars
    used = [i for i in range(k) if any(m[i] for m in p.monoms())]
    if len(used) == 1:
        import flint

        i = used[0]
        coeffs: dict[int, Any] = {}
        for m, c in zip(p.monoms(), p.coeffs()):
            coeffs[int(m[i])] = c
        uni = flint.fmpq_poly([coeffs.get(e, 0) for e in range(max(coeffs) + 1)])
        roots: Any = uni.numer().complex_roots()
        for root, _ in roots:
            if root.imag.is_zero() and not (root.real > 1 or root.real < -1):
                return False  # a real root in [-1, 1] (or too close to its ends to say): refused
        return True
    from lyapcheck.models.loop.positivity import prove_positive_on_box
    from lyapcheck.models.engines.search import Budget

    budget = Budget(30.0, "lyapcheck.models.loop.boxes: a box's definedness proof")
    return prove_positive_on_box(ring, p, budget) is not None or prove_positive_on_box(ring, -p, budget) is not None
