"""Parameter validation: every kind of bad input gives one InvalidParameter naming the field."""

from __future__ import annotations

import math
from fractions import Fraction
from pathlib import Path

import pytest

from lyapcheck.errors import InputFileError, InvalidParameter
from lyapcheck.paper.params import problem_from_sources
from tests.conftest import PAPER_TOML


def test_paper_values_are_si_and_exact(paper_problem) -> None:
    g = paper_problem.gains
    assert g.delta_los == Fraction(3, 4000)  # 0.75 mm exactly
    assert paper_problem.swimmer.e11 == Fraction(93, 10**6)
    assert paper_problem.d_max == Fraction(88, 10**6)  # 0.088 mm/s
    assert g.alpha_d == 600 and g.sigma0 == Fraction(1, 100) and g.k_d == Fraction(3, 20)


def test_rotation_frequency_in_hz_becomes_angular_velocity(paper_problem) -> None:
    # 2.8 Hz is 2.8 cycles per second = 2*pi*2.8 rad/s, not 2.8 rad/s (pint alone would say 2.8)
    assert math.isclose(float(paper_problem.actuation.omega_so), 2 * math.pi * 2.8, rel_tol=1e-12)
    assert math.isclose(paper_problem.actuation.omega_so_hz, 2.8, rel_tol=1e-12)
    rad = problem_from_sources(PAPER_TOML, {"actuation.omega_so": "17.59 rad/s"})
    assert math.isclose(float(rad.actuation.omega_so), 17.59, rel_tol=1e-12)
    rpm = problem_from_sources(PAPER_TOML, {"actuation.omega_so": "60 rpm"})
    assert math.isclose(float(rpm.actuation.omega_so), 2 * math.pi, rel_tol=1e-12)


@pytest.mark.parametrize(
    ("key", "value", "field", "fragment"),
    [
        ("gains.alpha_d", -1, "alpha_d", "(0, inf)"),
        ("gains.alpha_d", 0, "alpha_d", "(0, inf)"),
        ("gains.sigma0", float("nan"), "sigma0", "finite"),
        ("gains.k_d", float("inf"), "k_d", "finite"),
        ("gains.delta_los", "0.75 Hz", "delta_los", "length"),
        ("gains.delta_los", "0.75", "delta_los", "with its unit"),
        ("gains.alpha_d", "abc", "alpha_d", "finite number"),
        ("gains.alpha_d", True, "alpha_d", "rate"),
        ("actuation.omega_so", "3 1/s", "omega_so", "ambiguous"),
        ("actuation.omega_so", "2.8 m", "omega_so", "rotation"),
        ("actuation.omega_so", "2 rad", "omega_so", "rotation"),
        ("disturbance.d_max", "-1 mm/s", "d_max", "[0, inf)"),
        ("swimmer.e11", "9.3e-5 parsec/fortnight", "e11", "length"),
        ("gains.bogus", 1, "gains.bogus", "known parameter"),
    ],
)
def test_bad_input_names_field_range_and_value(key: str, value: object, field: str, fragment: str) -> None:
    with pytest.raises(InvalidParameter, match=r"^The '" + field.replace(".", r"\.") + r"' parameter must be") as info:
        problem_from_sources(PAPER_TOML, {key: value})
    message = str(info.value)
    assert fragment in message and "Got" in message and "\n" not in message


def test_unknown_key_and_section_in_toml(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('[gains]\nalpha_d = 600\nalpha = 3\n')
    with pytest.raises(InvalidParameter, match="gains.alpha"):
        problem_from_sources(bad, {})
    bad.write_text('[gainz]\nalpha_d = 600\n')
    with pytest.raises(InvalidParameter, match="gainz"):
        problem_from_sources(bad, {})


def test_missing_required_field_is_named(tmp_path: Path) -> None:
    partial = tmp_path / "partial.toml"
    partial.write_text('[gains]\nalpha_d = 600\n')
    with pytest.raises(InvalidParameter, match="'sigma0'"):
        problem_from_sources(partial, {})


def test_missing_and_corrupt_files(tmp_path: Path) -> None:
    with pytest.raises(InputFileError, match="does not exist"):
        problem_from_sources(tmp_path / "nope.toml", {})
    broken = tmp_path / "broken.toml"
    broken.write_text("[gains\nalpha_d = ")
    with pytest.raises(InputFileError, match="not valid TOML"):
        problem_from_sources(broken, {})


def test_problem_is_immutable(paper_problem) -> None:
    with pytest.raises(AttributeError):
        paper_problem.gains.alpha_d = Fraction(1)  # type: ignore[misc]
