"""The generated exact closed loop is the derivation's output, byte for byte."""

from __future__ import annotations

from fractions import Fraction

from hypothesis import given, settings
from hypothesis import strategies as st

from symbolic import _generated, codegen
from symbolic.closed_loop import evaluate


def test_generated_file_is_in_sync_with_the_derivation() -> None:
    assert codegen.TARGET.read_text() == codegen.render(), "run: python -m symbolic.codegen"


positive = st.fractions(min_value=Fraction(1, 1000), max_value=1000, max_denominator=1000)


@settings(max_examples=40, derandomize=True, deadline=None)
@given(st.tuples(*[positive] * 7), st.sampled_from(["derived", "printed"]))
def test_generated_values_equal_sympy_evaluation(values: tuple[Fraction, ...], name: str) -> None:
    kwargs = dict(zip(codegen.ARGS, values))
    fast = getattr(_generated, name)(**kwargs)
    slow = evaluate(name, kwargs)  # type: ignore[arg-type]
    assert fast["A"] == slow.A and fast["B"] == slow.B and fast["E"] == slow.E
    assert fast["rho_sup"] == slow.rho_sup
