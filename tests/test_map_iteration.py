"""One loop iterates every discrete-time map (:mod:`lyapcheck.models.engines.iteration`): a row that leaves
the escape box is frozen at the iterate where it left, the others go on; without a box every row is
iterated every step; the observer sees exactly the rows iterated; a row that meets the caller's `stop` is frozen
there, and an observer that returns True ends the iteration."""

from __future__ import annotations

import numpy as np

from lyapcheck.models.engines.iteration import iterate_map, stacked_map


def halve_or_triple(x: np.ndarray) -> np.ndarray:
    """x/2 for |x| < 1, 3x beyond: the first row converges, the second runs away."""
    return np.where(np.abs(x) < 1, x / 2, 3 * x)


def test_a_row_that_leaves_the_box_is_frozen_where_it_left_and_the_others_go_on() -> None:
    starts = np.array([[0.5, -0.5], [2.0, 0.0]])
    seen: list[tuple[int, list[int]]] = []
    x, alive = iterate_map(halve_or_triple, starts, 10, escape=np.array([100.0, 100.0]),
                           observe=lambda k, rows, xs: seen.append((k, rows.tolist())))
    assert alive.tolist() == [True, False]
    np.testing.assert_allclose(x[0], [0.5 / 2**10, -0.5 / 2**10])
    np.testing.assert_allclose(x[1], [2.0 * 3**4, 0.0])  # 162 > 100 after 4 steps: kept, not iterated again
    assert seen[:4] == [(k, [0, 1]) for k in range(1, 5)] and all(rows == [0] for _, rows in seen[4:])
    assert starts[1, 0] == 2.0  # the starts are not changed


def test_the_box_is_around_its_centre_and_a_non_finite_row_leaves_it() -> None:
    starts = np.array([[10.0], [np.inf]])
    x, alive = iterate_map(lambda x: x, starts, 3, center=np.array([10.0]), escape=1.0)
    assert alive.tolist() == [True, False]


def test_without_a_box_every_row_is_iterated_every_step() -> None:
    starts = np.array([[0.5], [2.0]])
    count = [0]

    def observe(k: int, rows: np.ndarray, xs: np.ndarray) -> None:
        assert rows.tolist() == [0, 1]
        count[0] += 1

    x, alive = iterate_map(stacked_map([lambda x: 3 * x[:, 0]]), starts, 5, observe=observe)
    assert count[0] == 5 and alive.all()
    np.testing.assert_allclose(x[:, 0], [0.5 * 3**5, 2.0 * 3**5])


def test_a_row_that_meets_stop_is_frozen_after_the_observer_saw_it_and_a_start_that_meets_it_never_moves() -> None:
    starts = np.array([[1.0], [0.1], [5.0]])  # doubling; stop at x >= 4: row 2 at once, row 0 after 2 steps
    seen: list[tuple[int, list[int], list[float]]] = []
    x, alive = iterate_map(lambda x: 2 * x, starts, 6, stop=lambda x: x[:, 0] >= 4,
                           observe=lambda k, rows, xs: seen.append((k, rows.tolist(), xs[:, 0].tolist())))
    assert alive.tolist() == [False, False, False]
    np.testing.assert_allclose(x[:, 0], [4.0, 6.4, 5.0])  # row 1: 0.1 * 2**6 = 6.4, stopped at the last step
    assert seen[0] == (1, [0, 1], [2.0, 0.2]) and seen[1] == (2, [0, 1], [4.0, 0.4])
    assert all(rows == [1] for _, rows, _ in seen[2:]) and len(seen) == 6


def test_an_observer_that_returns_true_ends_the_iteration_after_that_step() -> None:
    steps: list[int] = []

    def observe(k: int, rows: np.ndarray, xs: np.ndarray) -> bool:
        steps.append(k)
        return bool(np.any(xs[:, 0] > 10))

    x, alive = iterate_map(lambda x: 3 * x, np.array([[1.0], [0.5]]), 20, observe=observe)
    assert steps == [1, 2, 3] and alive.all()  # 27 > 10 after step 3; nothing frozen
    np.testing.assert_allclose(x[:, 0], [27.0, 13.5])
