"""The one way a parameter box is written (:func:`lyapcheck.models.language.parameter_box.box_text`): a split part
narrower than 6 significant digits no longer reads ``k in [1, 1]`` (issue 44, found not fixed).

What is asserted: a box of usual width reads as before (6 significant digits, ``%g``); each half of a box split
down to widths of ``1e-9`` reads with two different ends, each the exact end rounded (read back, within half a
unit of its last printed digit, in order); two ends that no double tells apart are written as exact rationals;
the model files' boxes (``ModelBox.describe``, what ``verify`` and the sweeps print), the paper's boxes and the
reports' tables (5 digits) go through it.
"""

from __future__ import annotations

from decimal import Decimal
from fractions import Fraction

import pytest

from lyapcheck.models.language.parameter_box import ModelBox, box_text, interval_ends


def _last_place(text: str) -> Fraction:
    """The place of the last digit written (``1.0000001`` -> ``1e-7``)."""
    return Fraction(10) ** Decimal(text).as_tuple().exponent


def test_a_box_of_usual_width_reads_as_before() -> None:
    box = ModelBox((("mu", Fraction(4, 5), Fraction(6, 5)), ("k", Fraction(1), Fraction(2))))
    assert box.describe() == "mu in [0.8, 1.2], k in [1, 2]"
    assert box_text([("g", 0.6000000000000001, 0.7000000000000001)]) == "g in [0.6, 0.7]"
    assert interval_ends(Fraction(1, 3), Fraction(2, 3)) == ("0.333333", "0.666667")


def test_the_halves_of_a_narrow_box_read_with_two_different_ends() -> None:
    box = ModelBox((("k", Fraction(1), Fraction(100001, 100000)),))
    seen = 0
    while box.bounds[0][2] - box.bounds[0][1] > Fraction(1, 10**9):
        box = box.split()[1]
        (name, lo, hi), = box.bounds
        text = box.describe()
        assert text.startswith("k in [") and text.endswith("]")
        low, high = text[len("k in ["):-1].split(", ")
        assert low != high, text
        for written, exact in ((low, lo), (high, hi)):
            assert abs(Fraction(written) - exact) <= _last_place(written) / 2, (written, exact)
        assert Fraction(low) < Fraction(high)
        seen += 1
    assert seen > 10  # (the loop reached widths far below 6 significant digits)


def test_ends_no_double_tells_apart_are_written_exactly() -> None:
    lo, hi = Fraction(3, 2), Fraction(3, 2) + Fraction(1, 10**20)
    assert float(lo) == float(hi)
    assert interval_ends(lo, hi) == ("3/2", "150000000000000000001/100000000000000000000")
    assert interval_ends(lo, lo) == ("1.5", "1.5")  # (a point is written once, as it is)


@pytest.mark.parametrize("digits, expected", [(6, "a in [2, 2.000001]"), (5, "a in [2, 2.000001]")])
def test_fewer_digits_grow_the_same_way(digits: int, expected: str) -> None:
    assert box_text([("a", 2.0, 2.000001)], digits=digits) == expected


def test_the_paper_s_box_and_the_reports_write_a_narrow_box_apart() -> None:
    from lyapcheck.paper.boxes.box import ParameterBox
    from reports.stores.model_file import _where_box

    narrow = ParameterBox((("alpha_d", Fraction(600), Fraction(600) + Fraction(1, 10**6)),))
    assert narrow.describe() == "alpha_d in [600, 600.000001]"
    assert _where_box(["k"], [1.0], [1.0 + 1e-7]) == "k in [1, 1.0000001]"
