"""The compiled per-point loops of the point-cloud normals (see :mod:`mesh_normal.kernels`).

One kernel does the work of estimation: for each point of a block, the mean of its neighbours,
their covariance about that mean (two passes, float64) and its symmetric eigen solve by cyclic
Jacobi rotations, which is accurate for flat, linear and isotropic neighbourhoods alike (no
closed form to fall back from). Rows run in parallel and write disjoint outputs, so the bits do
not depend on the number of cores. Two more serve the orientation: the neighbour graph's edges
and their weights, and signs carried down its spanning tree.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mesh_normal.kernels import dot, kernel, prange
from mesh_normal.tolerances import POINT_GAP_RATIO, POINT_LINE_RATIO
from mesh_normal.types import BoolArray, FloatArray, IndexArray

# The estimation codes, as the kernel writes them (the values of ``PointStatus``).
OK, TOO_FEW_NEIGHBOURS, DUPLICATES, COLLINEAR, AMBIGUOUS = 0, 2, 3, 4, 5

#: Jacobi sweeps at most: a 3 x 3 matrix converges quadratically, in 4 or 5.
_SWEEPS = 16


@kernel()
def _rotate(a: FloatArray, v: FloatArray, p: int, q: int) -> None:
    """One Jacobi rotation that zeroes ``a[p, q]``: a = J^T a J and v = v J."""
    apq = a[p, q]
    if apq == 0.0:
        return
    theta = (a[q, q] - a[p, p]) / (2.0 * apq)
    if abs(theta) > 1e150:  # theta**2 would overflow: t is then 1 / (2 theta) to rounding
        t = 0.5 / theta
    else:
        t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
        if theta < 0.0:
            t = -t
    c = 1.0 / math.sqrt(t * t + 1.0)
    s = t * c
    for k in range(3):
        akp, akq = a[k, p], a[k, q]
        a[k, p], a[k, q] = c * akp - s * akq, s * akp + c * akq
    for k in range(3):
        apk, aqk = a[p, k], a[q, k]
        a[p, k], a[q, k] = c * apk - s * aqk, s * apk + c * aqk
    a[p, q] = a[q, p] = 0.0
    for k in range(3):
        vkp, vkq = v[k, p], v[k, q]
        v[k, p], v[k, q] = c * vkp - s * vkq, s * vkp + c * vkq


@kernel()
def symmetric_eigen(a: FloatArray, v: FloatArray) -> None:
    """Diagonalise the symmetric 3 x 3 ``a`` in place; ``v`` gets the eigenvectors as columns.

    The eigenvalues are left on the diagonal of ``a``, unsorted.
    """
    for i in range(3):
        for j in range(3):
            v[i, j] = 1.0 if i == j else 0.0
    for _ in range(_SWEEPS):
        off = a[0, 1] ** 2 + a[0, 2] ** 2 + a[1, 2] ** 2
        diagonal = a[0, 0] ** 2 + a[1, 1] ** 2 + a[2, 2] ** 2
        if off <= 1e-36 * diagonal or off == 0.0:
            return
        _rotate(a, v, 0, 1)
        _rotate(a, v, 0, 2)
        _rotate(a, v, 1, 2)


@kernel()
def _covariance(
    points: FloatArray, neighbours: IndexArray, start: int, stop: int, a: FloatArray
) -> int:
    """The covariance of ``points[neighbours[start:stop]]`` about its mean, into ``a``.

    Entries of ``neighbours`` out of range (a k-d tree's "missing") are skipped; returns how
    many points were used.
    """
    n = len(points)
    count = 0
    mx, my, mz = 0.0, 0.0, 0.0
    for e in range(start, stop):
        j = neighbours[e]
        if 0 <= j < n:
            mx += points[j, 0]
            my += points[j, 1]
            mz += points[j, 2]
            count += 1
    for i in range(3):
        for j in range(3):
            a[i, j] = 0.0
    if count == 0:
        return 0
    mx, my, mz = mx / count, my / count, mz / count
    for e in range(start, stop):
        j = neighbours[e]
        if 0 <= j < n:
            x, y, z = points[j, 0] - mx, points[j, 1] - my, points[j, 2] - mz
            a[0, 0] += x * x
            a[0, 1] += x * y
            a[0, 2] += x * z
            a[1, 1] += y * y
            a[1, 2] += y * z
            a[2, 2] += z * z
    for i in range(3):
        for j in range(i, 3):
            a[i, j] /= count
            a[j, i] = a[i, j]
    return count


@kernel()
def _classify(low: float, middle: float, high: float, count: int, tiny: float) -> int:
    """The estimation code of a neighbourhood with sorted eigenvalues low <= middle <= high."""
    if count < 3:
        return TOO_FEW_NEIGHBOURS
    if high <= tiny:
        return DUPLICATES
    if middle <= tiny + POINT_LINE_RATIO * high:
        return COLLINEAR
    if middle - low <= tiny + POINT_GAP_RATIO * high:
        return AMBIGUOUS
    return OK


@kernel(parallel=True)
def neighbourhood_normals(
    points: FloatArray,
    indptr: IndexArray,
    neighbours: IndexArray,
    tiny: float,
    normals: FloatArray,
    curvature: FloatArray,
    used: IndexArray,
    status: IndexArray,
) -> None:
    """Row r of the outputs from the points ``neighbours[indptr[r]:indptr[r + 1]]``.

    ``tiny`` is the variance that rounding of the coordinates alone could give (see
    :mod:`mesh_normal.points.estimate`). ``normals`` get the eigenvector of the smallest
    eigenvalue, its largest component positive (a canonical sign: orientation comes later),
    or zero where the status is not OK; ``curvature`` is low / (low + middle + high), or 0 where
    the points coincide or are fewer than three.
    """
    rows = len(indptr) - 1
    block = 256
    for b in prange((rows + block - 1) // block):  # disjoint rows: every core
        a, v = np.empty((3, 3)), np.empty((3, 3))
        for r in range(b * block, min(rows, (b + 1) * block)):
            count = _covariance(points, neighbours, indptr[r], indptr[r + 1], a)
            symmetric_eigen(a, v)
            e0, e1, e2 = max(a[0, 0], 0.0), max(a[1, 1], 0.0), max(a[2, 2], 0.0)
            # The column of the smallest eigenvalue; the other two sorted.
            if e0 <= e1 and e0 <= e2:
                column, low, middle, high = 0, e0, min(e1, e2), max(e1, e2)
            elif e1 <= e2:
                column, low, middle, high = 1, e1, min(e0, e2), max(e0, e2)
            else:
                column, low, middle, high = 2, e2, min(e0, e1), max(e0, e1)
            code = _classify(low, middle, high, count, tiny)
            used[r], status[r] = count, code
            trace = low + middle + high
            curvature[r] = low / trace if count >= 3 and high > tiny else 0.0
            x, y, z = v[0, column], v[1, column], v[2, column]
            largest = x if abs(x) >= abs(y) and abs(x) >= abs(z) else (y if abs(y) >= abs(z) else z)
            scale = (
                0.0
                if code != OK
                else (1.0 if largest > 0 else -1.0) / math.sqrt(x * x + y * y + z * z)
            )
            normals[r, 0] = x * scale + 0.0  # -0.0 becomes 0.0
            normals[r, 1] = y * scale + 0.0
            normals[r, 2] = z * scale + 0.0


@kernel()
def propagate_signs(
    order: IndexArray,
    parent: IndexArray,
    agrees: BoolArray,
    sharp: BoolArray,
    seed_flip: BoolArray,
) -> tuple[BoolArray, BoolArray]:
    """Signs carried from each tree's root down a breadth-first ``order``.

    ``parent[i]`` is i's predecessor in the tree (negative at a root); ``agrees[i]`` whether
    i's normal points the same way as its parent's (their dot product is positive), ``sharp[i]``
    whether the edge to its parent is too sharp to carry a sign, and ``seed_flip[i]``, at a
    root, whether the root must be flipped. Returns ``flip`` and ``cut``: a point is cut (left
    unoriented, not flipped) when the path from its root crosses a sharp edge.
    """
    n = len(parent)
    flip = np.zeros(n, dtype=np.bool_)
    cut = np.zeros(n, dtype=np.bool_)
    for i in order:
        p = parent[i]
        if p < 0:
            flip[i] = seed_flip[i]
        else:
            cut[i] = sharp[i] or cut[p]
            flip[i] = (flip[p] != (not agrees[i])) and not cut[i]
    return flip, cut


@kernel()
def _listed(graph: NDArray[np.int32], row: int, value: int) -> bool:
    found = False
    for c in range(graph.shape[1]):
        found |= graph[row, c] == value
    return found


@kernel()
def graph_edges(
    points: FloatArray,
    normals: FloatArray,
    valid: BoolArray,
    graph: NDArray[np.int32],
    floor: float,
    sine_limit: float,
    rows: NDArray[np.int32],
    cols: NDArray[np.int32],
    weights: FloatArray,
) -> int:
    """The edges of the neighbour graph between valid points, each once, into the outputs.

    Weight 1 - |n_i . n_j| + ``floor``. With ``sine_limit`` below 1 (the ``"riemannian"``
    graph), an edge leaves out where the step between the points leaves either tangent plane
    by a sine over it, and otherwise weighs that sine more. Returns how many were written.
    """
    count = 0
    for i in range(len(graph)):
        if not valid[i]:
            continue
        ni = (normals[i, 0], normals[i, 1], normals[i, 2])
        for c in range(graph.shape[1]):
            j = graph[i, c]
            if j < 0 or j == i or not valid[j] or (j < i and _listed(graph, j, i)):
                continue  # (j, i) was written from j's list
            nj = (normals[j, 0], normals[j, 1], normals[j, 2])
            weight = 1.0 - abs(dot(ni, nj)) + floor
            if sine_limit < 1.0:
                step = (
                    points[j, 0] - points[i, 0],
                    points[j, 1] - points[i, 1],
                    points[j, 2] - points[i, 2],
                )
                length = math.sqrt(dot(step, step))
                sine = (
                    0.0 if length == 0.0 else max(abs(dot(step, ni)), abs(dot(step, nj))) / length
                )
                if sine > sine_limit:
                    continue
                weight += sine
            rows[count], cols[count], weights[count] = i, j, weight
            count += 1
    return count


#: Every kernel of this module, for :func:`mesh_normal.kernels.announce_compiling`: a point
#: cloud's estimate and orientation run these and no mesh kernel.
KERNELS = (
    _rotate,
    symmetric_eigen,
    _covariance,
    _classify,
    neighbourhood_normals,
    propagate_signs,
    _listed,
    graph_edges,
)
