"""The Analytic Hierarchy Process (Saaty), used to weigh plan criteria.

HATP scores a plan on several heterogeneous criteria (cost, duration, human
effort, the penalty of each social rule...) and its evaluation follows the
Analytic Hierarchy Process.  Rather than asking for the weights directly, AHP
asks for *pairwise comparisons*: ``a[i][j]`` says how much more important
criterion ``i`` is than criterion ``j`` (Saaty's scale: 1 equal, 3 moderately,
5 strongly, 7 very strongly, 9 extremely more important, 2, 4, 6, 8 in between,
and the reciprocals for "less important").  The matrix is *reciprocal*:
``a[j][i] = 1 / a[i][j]`` and ``a[i][i] = 1``.

Why the principal eigenvector.  If the judgements were perfectly consistent,
they would be ratios of true weights, ``a[i][j] = w[i] / w[j]``; then
``A w = n w``: ``w`` is an eigenvector of ``A`` for the eigenvalue ``n``, and
every column of ``A`` is proportional to it.  Real judgements are not exactly
consistent; the eigenvector of the largest eigenvalue (the Perron vector,
strictly positive for a positive matrix) is the weight vector that best
explains all the comparisons at once, each weight being the average of its
row's ratios weighted by the others' weights.

What the consistency ratio means.  For a positive reciprocal matrix the
largest eigenvalue ``lambda_max`` is at least ``n``, and equals ``n`` exactly
when the matrix is consistent.  The *consistency index*
``CI = (lambda_max - n) / (n - 1)`` measures how far it is from that; the
*consistency ratio* ``CR = CI / RI`` compares it with the mean index ``RI`` of
random reciprocal matrices of the same size (:data:`RANDOM_INDEX`).  Saaty's
rule of thumb accepts ``CR <= 0.1``: above that, the comparisons contradict
each other too much (e.g. "cost beats time, time beats effort, effort beats
cost") and should be revised, so :func:`priority_vector` refuses them.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy

RANDOM_INDEX: dict[int, float] = {
    1: 0.0, 2: 0.0, 3: 0.58, 4: 0.90, 5: 1.12, 6: 1.24, 7: 1.32, 8: 1.41,
    9: 1.45, 10: 1.49, 11: 1.51, 12: 1.48, 13: 1.56, 14: 1.57, 15: 1.59,
}
"""Saaty's random index: the mean consistency index of random reciprocal
matrices of size ``n`` (n = 1..15)."""

MAX_CONSISTENCY_RATIO = 0.1
"""Comparisons whose consistency ratio exceeds this are refused."""

RECIPROCAL_TOLERANCE = 1e-6
"""How far from 1 ``a[i][j] * a[j][i]`` (and ``a[i][i]``) may be."""

_ZERO = 1e-12


class AHPError(ValueError):
    """A pairwise comparison matrix that AHP cannot (or should not) use.

    ``row`` and ``col`` (0-based) point at the offending cell when there is one.
    """

    def __init__(self, message: str, row: int | None = None, col: int | None = None):
        super().__init__(message)
        self.message = message
        self.row = row
        self.col = col


@dataclass(frozen=True)
class AHPResult:
    """The priority vector of a comparison matrix and how consistent the matrix is."""

    weights: tuple[float, ...]
    """One weight per criterion (row order), all positive, summing to 1."""
    lambda_max: float
    """The principal eigenvalue (``n`` for a perfectly consistent matrix)."""
    consistency_index: float
    """``CI = (lambda_max - n) / (n - 1)``; 0 when n <= 2."""
    consistency_ratio: float
    """``CR = CI / RI(n)``; 0 when n <= 2."""


def _check(matrix: list[list[float]]) -> int:
    """Check the shape and the entries of ``matrix``; return its size."""
    if not isinstance(matrix, (list, tuple)) or not matrix:
        raise AHPError("the comparison matrix is empty: give one row per criterion")
    n = len(matrix)
    for i, row in enumerate(matrix):
        if not isinstance(row, (list, tuple)):
            raise AHPError(f"row {i} is not a list of numbers", row=i)
        if len(row) != n:
            raise AHPError(f"the comparison matrix is not square: {n} rows but row {i} "
                           f"has {len(row)} entries", row=i)
    if n > max(RANDOM_INDEX):
        raise AHPError(f"too many criteria ({n}): the random index is known for at most "
                       f"{max(RANDOM_INDEX)}; group the criteria into a hierarchy")
    for i, row in enumerate(matrix):
        for j, value in enumerate(row):
            if (isinstance(value, bool) or not isinstance(value, numbers.Real)
                    or not math.isfinite(value) or value <= 0):
                raise AHPError(f"a[{i}][{j}] = {value!r} is not a positive number "
                               f"(use Saaty's scale 1/9..9)", row=i, col=j)
    for i in range(n):
        if abs(matrix[i][i] - 1) > RECIPROCAL_TOLERANCE:
            raise AHPError(f"a[{i}][{i}] = {matrix[i][i]!r}: a criterion compared with "
                           f"itself must be 1", row=i, col=i)
    for i in range(n):
        for j in range(i + 1, n):
            product = matrix[i][j] * matrix[j][i]
            if abs(product - 1) > RECIPROCAL_TOLERANCE:
                raise AHPError(f"not reciprocal at a[{i}][{j}]: a[{i}][{j}] = "
                               f"{matrix[i][j]!r} but a[{j}][{i}] = {matrix[j][i]!r} "
                               f"(their product must be 1)", row=i, col=j)
    return n


def priority_vector(matrix: list[list[float]]) -> AHPResult:
    """The AHP weights of the criteria compared pairwise in ``matrix``.

    ``matrix[i][j]`` is how much more important criterion ``i`` is than ``j``.
    The weights are the principal eigenvector, normalised to sum 1.  Raises
    :class:`AHPError` if the matrix is empty, not square, has a non-positive
    entry, a diagonal entry other than 1, a non-reciprocal pair (the cell is
    given) or a consistency ratio above 0.1.
    """
    n = _check(matrix)
    if n == 1:
        return AHPResult(weights=(1.0,), lambda_max=1.0, consistency_index=0.0,
                         consistency_ratio=0.0)
    a = numpy.array(matrix, dtype=float)
    values, vectors = numpy.linalg.eig(a)
    # The Perron root of a positive matrix is real and is the largest eigenvalue;
    # the others may be complex.  Prefer (nearly) real eigenvalues, then the largest.
    real = numpy.abs(values.imag) <= 1e-9 * max(1.0, float(numpy.abs(values).max()))
    candidates = numpy.where(real, values.real, -numpy.inf)
    k = int(numpy.argmax(candidates))
    lambda_max = float(values[k].real)
    vector = vectors[:, k].real
    total = float(vector.sum())
    if total == 0 or not numpy.all(vector / total > 0):
        raise AHPError("no positive principal eigenvector (numerical trouble with the "
                       "comparison matrix)")
    weights = tuple(float(w) for w in vector / total)
    if n <= 2:
        ci = cr = 0.0
    else:
        ci = max(0.0, (lambda_max - n) / (n - 1))
        if ci < _ZERO:
            ci = 0.0
        cr = ci / RANDOM_INDEX[n]
    if cr > MAX_CONSISTENCY_RATIO:
        raise AHPError(f"inconsistent comparisons: CR = {cr:.2f} > "
                       f"{MAX_CONSISTENCY_RATIO:.2f} (lambda_max = {lambda_max:.3f} for "
                       f"{n} criteria); revise the judgements so that they agree")
    return AHPResult(weights=weights, lambda_max=lambda_max, consistency_index=ci,
                     consistency_ratio=cr)
