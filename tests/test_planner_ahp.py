"""The Analytic Hierarchy Process: priority vectors, consistency, refusals."""

from __future__ import annotations

import dataclasses
from fractions import Fraction

import numpy
import pytest

from planner.evaluation.ahp import RANDOM_INDEX, AHPError, AHPResult, priority_vector


def test_consistent_3x3_gives_the_exact_ratios():
    result = priority_vector([[1, 2, 4], [1 / 2, 1, 2], [1 / 4, 1 / 2, 1]])
    assert isinstance(result, AHPResult)
    assert result.weights == pytest.approx((4 / 7, 2 / 7, 1 / 7), abs=1e-12)
    assert result.lambda_max == pytest.approx(3.0, abs=1e-9)
    assert result.consistency_index == 0.0
    assert result.consistency_ratio == 0.0
    assert all(isinstance(w, float) for w in result.weights)


def test_consistent_matrix_from_true_weights_gives_them_back():
    true = [0.5, 0.25, 0.15, 0.1]
    matrix = [[wi / wj for wj in true] for wi in true]
    result = priority_vector(matrix)
    assert result.weights == pytest.approx(tuple(true), abs=1e-12)
    assert result.lambda_max == pytest.approx(4.0)
    assert result.consistency_ratio == pytest.approx(0.0, abs=1e-12)


def test_slightly_inconsistent_matrix_is_accepted_with_its_consistency_ratio():
    # A textbook example: weights about 0.157, 0.594, 0.249, CR about 0.046.
    matrix = [[1, 1 / 3, 1 / 2], [3, 1, 3], [2, 1 / 3, 1]]
    result = priority_vector(matrix)
    assert result.weights == pytest.approx((0.1571, 0.5936, 0.2493), abs=1e-4)
    assert sum(result.weights) == pytest.approx(1.0)
    assert result.lambda_max == pytest.approx(3.0536, abs=1e-4)
    assert result.consistency_index == pytest.approx((result.lambda_max - 3) / 2)
    assert result.consistency_ratio == pytest.approx(result.consistency_index / 0.58)
    assert 0.04 < result.consistency_ratio < 0.05
    # The weights are the principal eigenvector: A w = lambda_max w.
    product = numpy.array(matrix) @ numpy.array(result.weights)
    assert product == pytest.approx(result.lambda_max * numpy.array(result.weights))


def test_fractions_are_numbers_too():
    matrix = [[Fraction(1), Fraction(3)], [Fraction(1, 3), Fraction(1)]]
    assert priority_vector(matrix).weights == pytest.approx((0.75, 0.25))


def test_one_criterion():
    result = priority_vector([[1]])
    assert result == AHPResult(weights=(1.0,), lambda_max=1.0, consistency_index=0.0,
                               consistency_ratio=0.0)


def test_two_criteria_are_always_consistent():
    result = priority_vector([[1, 9], [1 / 9, 1]])
    assert result.weights == pytest.approx((0.9, 0.1))
    assert result.lambda_max == pytest.approx(2.0)
    assert result.consistency_index == 0.0 and result.consistency_ratio == 0.0


def test_result_is_frozen():
    result = priority_vector([[1, 2], [0.5, 1]])
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.weights = (0.5, 0.5)  # type: ignore[misc]


def test_cyclic_judgements_are_refused():
    # cost > time > effort > cost: no weights can explain that.
    with pytest.raises(AHPError, match=r"^inconsistent comparisons: CR = \d+\.\d\d > 0\.10"):
        priority_vector([[1, 3, 1 / 3], [1 / 3, 1, 3], [3, 1 / 3, 1]])


def test_known_inconsistent_4x4_is_refused_with_its_ratio():
    matrix = [[1, 5, 6, 7], [1 / 5, 1, 4, 6], [1 / 6, 1 / 4, 1, 4], [1 / 7, 1 / 6, 1 / 4, 1]]
    with pytest.raises(AHPError, match=r"CR = 0\.14 > 0\.10") as caught:
        priority_vector(matrix)
    assert caught.value.row is None and caught.value.col is None


def test_non_reciprocal_cell_is_reported_with_its_position():
    matrix = [[1, 2, 4], [1 / 2, 1, 2], [1 / 4, 1 / 3, 1]]
    with pytest.raises(AHPError, match=r"a\[1\]\[2\]") as caught:
        priority_vector(matrix)
    assert (caught.value.row, caught.value.col) == (1, 2)
    assert isinstance(caught.value, ValueError)


def test_rounded_reciprocals_beyond_the_tolerance_are_refused():
    with pytest.raises(AHPError, match="not reciprocal"):
        priority_vector([[1, 3], [0.33, 1]])
    # ... but floating-point reciprocals are fine.
    priority_vector([[1, 7], [1 / 7, 1]])


@pytest.mark.parametrize("matrix, message", [
    ([], "empty"),
    ([[1, 2], [0.5]], "not square"),
    ([[1, 2, 3], [0.5, 1, 2]], "not square"),
    ([1, 2], "not a list"),
])
def test_shape_is_checked(matrix, message):
    with pytest.raises(AHPError, match=message):
        priority_vector(matrix)


@pytest.mark.parametrize("bad", [0, -2, float("nan"), float("inf"), "3", None, True])
def test_entries_must_be_positive_numbers(bad):
    with pytest.raises(AHPError, match="not a positive number") as caught:
        priority_vector([[1, bad], [0.5, 1]])
    assert (caught.value.row, caught.value.col) == (0, 1)


def test_diagonal_must_be_one():
    with pytest.raises(AHPError, match="itself must be 1") as caught:
        priority_vector([[1, 2], [0.5, 2]])
    assert (caught.value.row, caught.value.col) == (1, 1)


def test_random_index_table():
    assert len(RANDOM_INDEX) == 15
    assert RANDOM_INDEX[1] == RANDOM_INDEX[2] == 0.0
    assert RANDOM_INDEX[3] == 0.58 and RANDOM_INDEX[10] == 1.49 and RANDOM_INDEX[15] == 1.59


def test_more_criteria_than_the_random_index_knows_are_refused():
    with pytest.raises(AHPError, match="too many criteria"):
        priority_vector([[1.0] * 16 for _ in range(16)])


def test_large_consistent_matrix():
    true = numpy.arange(1, 16, dtype=float)
    true /= true.sum()
    matrix = [[float(wi / wj) for wj in true] for wi in true]
    result = priority_vector(matrix)
    assert result.weights == pytest.approx(tuple(true), abs=1e-10)
    assert result.consistency_ratio == pytest.approx(0.0, abs=1e-9)
