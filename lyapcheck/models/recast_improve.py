"""Enlarging a recast loop's region of attraction beyond the linearization's quadratic V."""

from __future__ import annotations

from typing import Any

from lyapcheck.sos.polynomials import Poly


def improved_candidates(loop: Any, V0: Poly, budget: Any) -> list[tuple[str, Poly]]:
    return []
